"""Planar scythe scene: swept cut test (speed, height, tunnelling, rotation), batching, parameters."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.scenes import InvalidSceneParameters, Scene, make_scene
from toolimit.scenes.planar.scythe import PlanarScytheScene
from toolimit.tools import ToolPose, tool_poses

FPS = 24.0
GRASS = np.array([1.0, 0.5, 0.0])


def straight_sweep(speed: float, height: float, wait: int = 2) -> ToolPose:
    """Blade along +y spanning the patch (0.45 m), handle straight up, swept along +x at ``speed``."""
    distance = 0.8
    xs = GRASS[0] - 0.4 + np.arange(int(np.ceil(distance / (speed / FPS))) + 1) * speed / FPS
    xs = np.concatenate([np.full(wait, xs[0]), xs])
    head = np.stack([xs, np.full_like(xs, GRASS[1] - 0.225), np.full_like(xs, height)], axis=1)
    return tool_poses(head, head + np.array([0.0, 0.0, 1.0]), roll=np.pi / 2)


def run(scene: PlanarScytheScene, poses: ToolPose, batch_size: int = 2, seed: int = 0) -> None:
    scene.reset({"grass_position": GRASS}, np.random.default_rng(seed), batch_size)
    for position, rotation in zip(poses.position, poses.rotation):
        scene.step(ToolPose(position, rotation))


def test_registry_builds_a_scene_with_the_protocol():
    scene = make_scene("scythe", "planar")
    assert isinstance(scene, Scene) and isinstance(scene, PlanarScytheScene)
    assert (scene.tool, scene.world) == ("scythe", "planar")
    assert [p.name for p in scene.parameters] == ["grass_position"]
    with pytest.raises(RuntimeError, match="call reset"):
        scene.goal_reward()
    with pytest.raises(RuntimeError, match="call reset"):
        scene.step(ToolPose(np.zeros(3), np.eye(3)))


@pytest.mark.parametrize("speed", [1.5, 4.0])
def test_fast_low_sweep_cuts_every_stalk_without_tunnelling(speed):
    """At 4 m/s the blade moves 17 cm per control step, far more than a stalk's width."""
    scene = PlanarScytheScene()
    run(scene, straight_sweep(speed, 0.05))
    np.testing.assert_array_equal(scene.goal_reward(), [scene.stalk_count] * 2)
    assert scene.is_success().all()


@pytest.mark.parametrize(("speed", "height"), [(0.5, 0.05), (2.0, 0.2)], ids=["too slow", "too high"])
def test_slow_or_high_sweep_cuts_nothing(speed, height):
    scene = PlanarScytheScene()
    run(scene, straight_sweep(speed, height))
    np.testing.assert_array_equal(scene.goal_reward(), [0.0, 0.0])
    assert not scene.is_success().any()
    assert np.all((scene.dense_reward() > 0.0) & (scene.dense_reward() <= 0.1))  # shaping without cuts


def test_dense_reward_grows_as_the_blade_root_approaches_the_stalks_in_the_x_y_plane():
    """0.1 mean exp(-5 d^2), d the x-y distance from the blade root to a stalk; the root's height is
    ignored (the plane's normal), the reward 0 before the first step."""
    scene = PlanarScytheScene()
    scene.reset({"grass_position": GRASS}, np.random.default_rng(0), batch_size=2)
    np.testing.assert_array_equal(scene.dense_reward(), [0.0, 0.0])  # no scythe yet
    rewards = []
    for offset in ([-1.5, 0.5, 0.3], [-0.5, 0.2, 0.6], [0.0, 0.0, 0.05]):
        root = GRASS + np.array(offset)
        scene.step(tool_poses(root, root + np.array([0.0, 0.0, 1.0])))
        expected = 0.1 * np.exp(-5.0 * np.sum((scene.stalks - root[:2]) ** 2, axis=-1)).mean(axis=1)
        np.testing.assert_allclose(scene.dense_reward(), expected, rtol=1e-12)
        rewards.append(scene.dense_reward())
    far, near, centre = rewards
    assert np.all((far > 0.0) & (far < near) & (near < centre) & (centre <= 0.1))


def test_rotating_blade_cuts_only_where_it_is_fast_enough():
    """The blade turns about its root at 2 pi rad/s: points nearer the root than v_min / omega
    = 0.16 m move too slowly to cut; the rest of its disc is cut."""
    omega = 2.0 * np.pi
    root = GRASS + np.array([0.0, 0.0, 0.05])
    angles = np.arange(0.0, 2.0 * np.pi + 1e-9, omega / FPS)
    axis = np.tile([0.0, 0.0, 1.0], (len(angles), 1))
    heads = np.tile(root, (len(angles), 1))
    scene = PlanarScytheScene(patch_diameter=0.6)
    run(scene, tool_poses(heads, heads + axis, roll=angles), batch_size=1)
    radius = np.linalg.norm(scene.stalks[0] - GRASS[:2], axis=1)
    cut = scene.cut[0]
    assert (radius > 0.17).sum() >= 10 and (radius < 0.15).sum() >= 3  # both groups are populated
    assert cut[radius > 0.17].all()
    assert not cut[radius < 0.15].any()


def test_same_seed_same_stalks_and_instances_differ():
    first, second = PlanarScytheScene(), PlanarScytheScene()
    first.reset({"grass_position": GRASS}, np.random.default_rng(3), 2)
    second.reset({"grass_position": GRASS}, np.random.default_rng(3), 2)
    np.testing.assert_array_equal(first.stalks, second.stalks)
    single = PlanarScytheScene()
    single.reset({"grass_position": GRASS}, np.random.default_rng(3), 1)
    np.testing.assert_array_equal(single.stalks[0], first.stalks[0])  # independent of the batch size
    assert not np.allclose(first.stalks[0], first.stalks[1])
    assert np.linalg.norm(first.stalks - GRASS[:2], axis=-1).max() <= first.patch_diameter / 2


def test_success_needs_the_cut_within_the_window():
    scene = PlanarScytheScene()
    run(scene, straight_sweep(2.0, 0.05, wait=30))  # the sweep starts after 1.25 s
    assert (scene.goal_reward() == scene.stalk_count).all() and not scene.is_success().any()


def test_invalid_parameters_are_rejected_with_a_reason():
    scene = PlanarScytheScene()
    far = {"grass_position": np.array([0.0, -7.0, 0.0])}
    assert "outside the world" in scene.invalid_reason(far)
    assert "missing parameter" in scene.invalid_reason({})
    with pytest.raises(InvalidSceneParameters, match="outside the world"):
        scene.reset(far, np.random.default_rng(0))


def test_footprints_and_snapshot():
    scene = PlanarScytheScene()
    scene.reset({"grass_position": GRASS}, np.random.default_rng(0))
    np.testing.assert_allclose(scene.footprints({"grass_position": GRASS}), [[1.0, 0.5, 0.2, 0.2, 0.0]])
    snapshot = scene.snapshot()
    assert snapshot["stalks"].shape == (scene.stalk_count, 3) and not snapshot["cut"].any()
    scene.step(ToolPose(np.array([0.0, 0.0, 0.05]), np.eye(3)))
    np.testing.assert_allclose(scene.snapshot()["blade"], [[0.0, 0.0, 0.05], [0.45, 0.0, 0.05]])
