"""Cutting model of the 3D scythe world (the authors' rule): distance, height, normal angle and
approach thresholds, the authors' size, determinism, the success window."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.scenes.base import CONTROL_FPS, InvalidSceneParameters, Scene
from toolimit.scenes.registry import make_scene
from toolimit.scenes.scythe_cut import scythe_cut_rule
from toolimit.scenes.spatial.scythe import SpatialScytheScene
from toolimit.scenes.spatial.sweep import (
    DRAW_SPEED,
    LEVEL,
    RAMP,
    edge_centre_offset,
    pull,
    ramped_distances,
    scripted_sweep,
)
from toolimit.tools import ToolPose, rotation_z, tool_spec

PATCH = np.array([1.0, -0.5, 0.0])


def fresh(batch_size=4, seed=0, **kwargs):
    scene = SpatialScytheScene(**kwargs)
    scene.reset({"grass_position": PATCH}, np.random.default_rng(seed), batch_size=batch_size)
    return scene


def run(scene, poses):
    for position, rotation in zip(poses.position, poses.rotation):
        scene.step(ToolPose(position, rotation))


def pull_across(scene, speed, height=0.05, x=PATCH[0], rotation=LEVEL, towards_handle=True):
    """The level edge (centred at ``x``) pulled across the patch along -y (towards the handle) at
    ``speed`` m/s, or pushed along +y; the poses' rotation may be replaced (same head path)."""
    start, end = PATCH[1] + 0.15, PATCH[1] - 0.15
    if not towards_handle:
        start, end = end, start
    poses = pull(np.array([x, 0.0, height]), start, end, speed, scene.control_dt)
    run(scene, ToolPose(poses.position, np.repeat(rotation[None], len(poses.position), axis=0)))


def test_registry_protocol_and_the_authors_size():
    scene = make_scene("scythe", "3d")
    assert isinstance(scene, Scene)
    assert [p.name for p in scene.parameters] == ["grass_position"]  # no yaw: the authors' has none
    assert (scene.n_stalks, scene.patch_size, scene.stalk_height, scene.stalk_width) == (10, (0.4, 0.1), 0.3, 0.005)
    spec = tool_spec("scythe")
    assert (spec.head_width, spec.length) == (0.35, 0.68)  # blade 0.35 m; snath 0.70 m less half the blade
    np.testing.assert_allclose(scene.edge, [[0.02, 0.0, 0.02], [0.37, 0.0, 0.02]])


def test_scripted_pulls_cut_every_stalk_within_the_first_second():
    scene = fresh(batch_size=20)
    run(scene, scripted_sweep({"grass_position": PATCH}))
    np.testing.assert_array_equal(scene.goal_reward(), scene.n_stalks)
    assert scene.is_success().all()
    assert np.all(scene.cut_time < 1.0)


def test_the_scripted_draw_holds_the_handle_up_and_crosses_the_patch_at_full_speed():
    """The handle end stands above the blade (where a robot grips), the edge moves towards the
    handle along the patch's length, from rest to rest, at DRAW_SPEED wherever it is over the patch."""
    poses = scripted_sweep({"grass_position": PATCH})
    handle = poses.position + tool_spec("scythe").length * poses.rotation[:, :, 2]
    assert np.all(handle[:, 2] - poses.position[:, 2] > 0.2)
    edge = poses.position + edge_centre_offset(poses.rotation[0])  # (T, 3), one rotation throughout
    step = np.diff(edge, axis=0) * CONTROL_FPS  # m/s between control steps
    assert np.all(step[:, 0] <= 1e-12) and np.allclose(step[:, 1:], 0.0)  # towards the handle: -x
    assert step[0, 0] == 0.0 and step[-1, 0] == 0.0
    over = np.abs(edge[1:, 0] - PATCH[0]) <= 0.2
    np.testing.assert_allclose(-step[over, 0], DRAW_SPEED, rtol=1e-9)


def test_ramped_distances_rise_hold_and_fall_at_the_given_speed():
    distances = ramped_distances(1.5, RAMP, 0.5, 1.0 / 240)
    speeds = np.diff(distances) * 240
    assert distances[0] == 0.0 and distances[-1] == pytest.approx(2 * RAMP + 0.5)
    assert np.all(speeds >= 0.0) and speeds.max() <= 1.5 + 1e-9
    assert speeds[0] < 0.01 and speeds[-1] < 0.05  # from rest, back to rest
    assert np.sum(np.isclose(speeds, 1.5)) * 1.5 / 240 == pytest.approx(0.5, abs=0.01)


@pytest.mark.parametrize("speed", [1.6, 2.4])
def test_a_fast_pull_cuts_the_stalks_under_the_edge(speed):
    """Stalks across the 0.35 m edge's span (the edge centred on the patch) are cut, none more than
    1 cm beyond its ends (there the direction to the stalk is more than 30 degrees off the normal
    wherever the stalk is within 2 cm)."""
    scene = fresh()
    pull_across(scene, speed)
    beyond = np.abs(scene.stalks_xy[..., 0] - PATCH[0]) - 0.175  # m beyond the nearer end
    assert np.all(scene.cut[beyond < 0.0]) and not np.any(scene.cut[beyond > 0.0101])
    assert (beyond < 0.0).sum() >= 30


def test_a_pull_below_about_one_metre_per_second_cuts_nothing():
    """The approach (velocity . offset, 0.02 m^2/s) needs > 1 m/s at the 2 cm limit."""
    scene = fresh()
    pull_across(scene, 0.9)
    assert scene.goal_reward().sum() == 0


def test_pushing_away_from_the_handle_cuts_nothing():
    scene = fresh()
    pull_across(scene, 3.0, towards_handle=False)
    assert scene.goal_reward().sum() == 0


def test_an_edge_above_the_cutting_height_cuts_nothing():
    scene = fresh()
    pull_across(scene, 3.0, height=scene.max_cut_height + 0.01)
    assert scene.goal_reward().sum() == 0


@pytest.mark.parametrize(("snath_elevation_deg", "cuts"), [(20.0, True), (40.0, False)])
def test_the_edge_normal_must_be_within_30_degrees_of_the_stalk(snath_elevation_deg, cuts):
    """The normal is the snath's direction towards the handle: raise the snath (turn about the
    blade, tool x) and beyond 30 degrees nothing is cut."""
    angle = np.deg2rad(snath_elevation_deg)
    turn = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(angle), -np.sin(angle)], [0.0, np.sin(angle), np.cos(angle)]])
    scene = fresh()
    pull_across(scene, 3.0, rotation=turn @ LEVEL)
    assert (scene.goal_reward().sum() > 0) == cuts


def test_the_rule_tests_the_distance_between_the_edge_and_the_stalk():
    """One stalk, the edge held still then moved 1 cm/sub-step towards it: cut at 2 cm or closer."""
    rule = scythe_cut_rule(0.005)
    stalk = np.array([[[0.2, -0.0495]]])  # (B=1, N=1, 2), 2.95 cm beyond the edge's y at the start
    # tool: head at the origin, level; the edge at y = -0.02 from the head
    positions = np.array([[[0.0, -0.01 * s, 0.05]] for s in range(4)])  # (S+1=4, B=1, 3)
    rotations = np.repeat(LEVEL[None, None], 4, axis=0)
    cuts = rule.cuts(positions, rotations, stalk, dt=1.0 / 240)  # 2.4 m/s towards the stalk
    # gaps after each sub-step: 1.95, 0.95, -0.05 cm (passed); approach 2.4 m/s * gap > 0.02 m^2/s
    np.testing.assert_array_equal(cuts[:, 0, 0], [True, True, False])


def test_stalks_lie_in_the_patch_and_depend_on_the_seed():
    scene = fresh()
    half = np.array(scene.patch_size) / 2
    assert np.all(np.abs(scene.stalks_xy - PATCH[:2]) <= half + 1e-12)
    assert not np.allclose(scene.stalks_xy[0], scene.stalks_xy[1])  # instances differ
    np.testing.assert_array_equal(fresh().stalks_xy, scene.stalks_xy)  # same seed, same grass
    assert not np.allclose(fresh(seed=1).stalks_xy, scene.stalks_xy)


def test_same_seed_same_rewards():
    results = []
    for _ in range(2):
        scene = fresh(batch_size=3)
        pull_across(scene, 1.3, x=PATCH[0] + 0.03)
        results.append((scene.goal_reward(), scene.dense_reward(), scene.is_success()))
    for a, b in zip(*results):
        np.testing.assert_array_equal(a, b)


def test_dense_reward_grows_as_the_head_point_approaches_the_patch_centre():
    """0.1 exp(-5 d^2), d from the head point (tool origin, the authors' tip) to the patch's centre
    on the ground (their one grass patch); 0 before the first step."""
    scene = fresh(batch_size=2)
    np.testing.assert_array_equal(scene.dense_reward(), [0.0, 0.0])  # no scythe yet
    rewards = []
    for offset in ([-0.2, -2.0, 0.05], [-0.2, -0.3, 0.05], [0.0, 0.0, 0.05]):
        root = PATCH + offset
        scene.step(ToolPose(root, LEVEL))
        expected = 0.1 * np.exp(-5.0 * np.sum((root - [PATCH[0], PATCH[1], 0.0]) ** 2))
        np.testing.assert_allclose(scene.dense_reward(), [expected, expected], rtol=1e-12)
        rewards.append(scene.dense_reward())
    far, near, centre = rewards
    assert np.all((far > 0.0) & (far < near) & (near < centre) & (centre <= 0.1))


def test_invalid_parameters_are_rejected_with_a_reason():
    scene = SpatialScytheScene()
    good = {"grass_position": PATCH}
    assert scene.invalid_reason(good) is None
    assert "ground" in scene.invalid_reason({"grass_position": PATCH + [0, 0, 0.1]})
    assert "missing" in scene.invalid_reason({})
    with pytest.raises(InvalidSceneParameters):
        scene.reset({"grass_position": np.array([9.0, 0.0, 0.0])}, np.random.default_rng(0))


def test_footprint_and_snapshot():
    scene = fresh()
    np.testing.assert_allclose(scene.footprints({"grass_position": PATCH}), [[1.0, -0.5, 0.2, 0.05, 0.0]])
    pull_across(scene, 3.0)
    snap = scene.snapshot()
    assert snap["stalk_base"].shape == (scene.n_stalks, 3)
    np.testing.assert_array_equal(snap["stalk_cut"], scene.cut[0])
    np.testing.assert_allclose(snap["blade"][1] - snap["blade"][0], [0.35, 0.0, 0.0], atol=1e-12)


def test_mowing_after_the_window_is_not_a_success():
    scene = fresh(batch_size=1)
    for _ in range(30):  # wait 1.25 s beside the patch before pulling
        scene.step(ToolPose(PATCH + [-0.2, 0.4, 0.05], LEVEL))
    run(scene, scripted_sweep({"grass_position": PATCH}))
    assert scene.goal_reward()[0] == scene.n_stalks
    assert not scene.is_success()[0]


def test_a_turned_scythe_cuts_along_its_own_snath():
    """The rule does not depend on the world's axes: the pull and the patch turned together about
    the patch centre cut the same stalks (the stalks turned with them)."""
    straight = fresh(batch_size=1)
    pull_across(straight, 2.5)
    turn = rotation_z(0.8)
    turned = fresh(batch_size=1)
    turned.stalks_xy = PATCH[:2] + (turned.stalks_xy - PATCH[:2]) @ turn[:2, :2].T
    start, end = PATCH[1] + 0.15, PATCH[1] - 0.15
    poses = pull(np.array([PATCH[0], 0.0, 0.05]), start, end, 2.5, turned.control_dt)
    positions = PATCH + (poses.position - PATCH) @ turn.T
    run(turned, ToolPose(positions, turn[None] @ poses.rotation))
    np.testing.assert_array_equal(turned.cut, straight.cut)
