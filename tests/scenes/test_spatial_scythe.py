"""Cutting model of the 3D scythe world: speed and height thresholds, swept tests, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.scenes.base import InvalidSceneParameters, Scene
from toolimit.scenes.registry import make_scene
from toolimit.scenes.spatial.scythe import SpatialScytheScene, edge_crossings
from toolimit.scenes.spatial.sweep import straight_sweep as sweep
from toolimit.tools import ToolPose, rotation_z

PATCH = np.array([1.0, -0.5, 0.0])
#: Blade along world x, cutting direction (tool +y) along world +y, snath straight up.
LEVEL = np.eye(3)


def fresh(batch_size=4, seed=0, yaw=0.0, **kwargs):
    scene = SpatialScytheScene(**kwargs)
    scene.reset({"grass_position": PATCH, "grass_yaw": yaw}, np.random.default_rng(seed), batch_size=batch_size)
    return scene


def straight_sweep(scene, speed, height, direction=1.0):
    """Sweep the level blade across the patch along +-y at ``speed`` (m/s), ``height`` (m) up."""
    for position, rotation in zip(*sweep(PATCH, 0.0, speed, height, scene.control_dt, direction)):
        scene.step(ToolPose(position, rotation))


def arc_sweep(scene, angular_speed, height, inner_radius=0.3):
    """Swing the level blade counterclockwise about a vertical axis beside the patch (rad/s).

    The edge lies along the radius, from ``inner_radius`` to ``inner_radius + blade_length`` from
    the pivot, and moves along tool +y (the cutting direction); returns the pivot (3,).
    """
    pivot = PATCH - np.array([inner_radius + scene.blade_length / 2, 0.0, 0.0])
    for angle in np.arange(-1.2, 1.2, angular_speed * scene.control_dt):
        turn = rotation_z(angle)
        scene.step(ToolPose(pivot + turn @ np.array([inner_radius, 0.0, height]), turn))
    return pivot


def test_registry_and_protocol():
    scene = make_scene("scythe", "3d")
    assert isinstance(scene, Scene)
    assert [p.name for p in scene.parameters] == ["grass_position", "grass_yaw"]


@pytest.mark.parametrize("speed", [1.5, 4.0])
def test_fast_low_sweep_cuts_all_stalks(speed):
    scene = fresh()
    straight_sweep(scene, speed, height=0.05)
    np.testing.assert_array_equal(scene.goal_reward(), scene.n_stalks)
    assert scene.is_success().all()


@pytest.mark.parametrize("angular_speed", [6.0, 2.5])
def test_arc_swing_cuts_where_the_edge_passes_fast_enough(angular_speed):
    """Stalks between the edge's radii are cut where the edge point's speed (omega r) > v_min."""
    scene = fresh(batch_size=2)
    inner = 0.3
    pivot = arc_sweep(scene, angular_speed, height=0.04, inner_radius=inner)
    radius = np.linalg.norm(scene.stalks_xy - pivot[:2], axis=-1)
    slowest = max(inner, scene.min_cut_speed / angular_speed)  # below this radius the edge is too slow
    expected = (radius > slowest) & (radius < inner + scene.blade_length)
    clear = (np.abs(radius - slowest) > 0.003) & (np.abs(radius - inner - scene.blade_length) > 0.003)
    np.testing.assert_array_equal(scene.cut[clear], expected[clear])
    if angular_speed < 3.0:  # the slow swing cuts only the outer stalks
        assert expected.any() and not expected.all()
    else:
        assert expected.all()


def test_sweep_below_min_speed_cuts_nothing():
    scene = fresh()
    straight_sweep(scene, 0.8 * scene.min_cut_speed, height=0.05)
    assert scene.goal_reward().sum() == 0


def test_sweep_above_max_height_cuts_nothing():
    scene = fresh()
    straight_sweep(scene, 3.0, height=scene.max_cut_height + 0.01)
    assert scene.goal_reward().sum() == 0


def test_backward_sweep_cuts_nothing():
    scene = fresh()
    straight_sweep(scene, 3.0, height=0.05, direction=-1.0)
    assert scene.goal_reward().sum() == 0


def test_no_tunnelling_at_4_m_per_s_with_one_substep():
    scene = fresh(substeps=1)
    straight_sweep(scene, 4.0, height=0.05)
    np.testing.assert_array_equal(scene.goal_reward(), scene.n_stalks)


def test_edge_crossings_of_a_rotating_edge_are_exact():
    """An edge turning a quarter turn about its root crosses a line at 45 degrees at f = 0.5."""
    root = np.zeros((1, 3))
    tip0, tip1 = np.array([[1.0, 0.0, 0.1]]), np.array([[0.0, 1.0, 0.1]])
    stalk = np.array([[[0.5, 0.5]]])
    fraction, along, height = edge_crossings(root, tip0, root, tip1, stalk)
    valid = np.isfinite(fraction[0, 0])
    assert valid.sum() == 1
    assert fraction[0, 0][valid][0] == pytest.approx(0.5)
    # the linearly moving tip passes (0.5, 0.5) exactly at mid-interval, end of the edge
    assert along[0, 0][valid][0] == pytest.approx(1.0)
    assert height[0, 0][valid][0] == pytest.approx(0.1)


def test_stalks_lie_in_the_turned_patch_and_depend_on_the_seed():
    yaw = 0.7
    scene = fresh(yaw=yaw)
    local = (scene.stalks_xy - PATCH[:2]) @ rotation_z(yaw)[:2, :2]
    half = np.array(scene.patch_size) / 2
    assert np.all(np.abs(local) <= half + 1e-12)
    assert not np.allclose(scene.stalks_xy[0], scene.stalks_xy[1])  # instances differ
    np.testing.assert_array_equal(fresh(yaw=yaw).stalks_xy, scene.stalks_xy)  # same seed, same grass
    assert not np.allclose(fresh(yaw=yaw, seed=1).stalks_xy, scene.stalks_xy)


def test_same_seed_same_rewards():
    results = []
    for _ in range(2):
        scene = fresh(batch_size=3, yaw=0.4)
        arc_sweep(scene, angular_speed=-5.0, height=0.05)
        results.append((scene.goal_reward(), scene.dense_reward(), scene.is_success()))
    for a, b in zip(*results):
        np.testing.assert_array_equal(a, b)


def test_dense_reward_grows_as_the_blade_root_approaches_the_stalks():
    """0.1 mean exp(-5 d^2), d from the blade root (tool origin) to the stalks at half the cutting
    height; 0 before the first step."""
    scene = fresh(batch_size=2)
    np.testing.assert_array_equal(scene.dense_reward(), [0.0, 0.0])  # no scythe yet
    rewards = []
    for offset in ([-0.2, -2.0, 0.05], [-0.2, -0.3, 0.05], [0.0, 0.0, 0.05]):
        root = PATCH + offset
        scene.step(ToolPose(root, LEVEL))
        stalk_points = np.concatenate([scene.stalks_xy, np.full((2, scene.n_stalks, 1), 0.05)], axis=-1)
        expected = 0.1 * np.exp(-5.0 * np.sum((stalk_points - root) ** 2, axis=-1)).mean(axis=1)
        np.testing.assert_allclose(scene.dense_reward(), expected, rtol=1e-12)
        rewards.append(scene.dense_reward())
    far, near, centre = rewards
    assert np.all((far > 0.0) & (far < near) & (near < centre) & (centre <= 0.1))


def test_invalid_parameters_are_rejected_with_a_reason():
    scene = SpatialScytheScene()
    good = {"grass_position": PATCH, "grass_yaw": 0.0}
    assert scene.invalid_reason(good) is None
    assert "ground" in scene.invalid_reason({**good, "grass_position": PATCH + [0, 0, 0.1]})
    assert "grass_yaw" in scene.invalid_reason({**good, "grass_yaw": 4.0})
    assert "missing" in scene.invalid_reason({"grass_position": PATCH})
    with pytest.raises(InvalidSceneParameters):
        scene.reset({**good, "grass_position": np.array([9.0, 0.0, 0.0])}, np.random.default_rng(0))


def test_footprint_and_snapshot():
    scene = fresh(yaw=0.3)
    np.testing.assert_allclose(scene.footprints({"grass_position": PATCH, "grass_yaw": 0.3}), [[1.0, -0.5, 0.2, 0.15, 0.3]])
    straight_sweep(scene, 3.0, height=0.05)
    snap = scene.snapshot()
    assert snap["stalk_base"].shape == (scene.n_stalks, 3)
    np.testing.assert_array_equal(snap["stalk_cut"], scene.cut[0])
    np.testing.assert_allclose(snap["blade"][1] - snap["blade"][0], [scene.blade_length, 0.0, 0.0])


def test_mowing_after_the_window_is_not_a_success():
    scene = fresh(batch_size=1)
    for _ in range(30):  # wait 1.25 s beside the patch before sweeping
        scene.step(ToolPose(PATCH + [-0.2, -0.4, 0.05], LEVEL))
    straight_sweep(scene, 3.0, height=0.05)
    assert scene.goal_reward()[0] == scene.n_stalks
    assert not scene.is_success()[0]
