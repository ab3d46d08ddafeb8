"""Planar scythe scene: the 3D scene's twin (same size, same cut rule, same cuts), batching,
parameters."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.scenes import InvalidSceneParameters, Scene, make_scene
from toolimit.scenes.planar.scythe import PlanarScytheScene
from toolimit.scenes.spatial.scythe import SpatialScytheScene
from toolimit.scenes.spatial.sweep import LEVEL, pull, scripted_sweep
from toolimit.tools import ToolPose, tool_poses

GRASS = np.array([1.0, 0.5, 0.0])


def run(scene, poses: ToolPose, batch_size: int = 2, seed: int = 0) -> None:
    scene.reset({"grass_position": GRASS}, np.random.default_rng(seed), batch_size)
    for position, rotation in zip(poses.position, poses.rotation):
        scene.step(ToolPose(position, rotation))


def pulled(speed: float, height: float, wait: int = 0) -> ToolPose:
    """The level scythe pulled across the patch at ``speed`` m/s, ``height`` m up, after ``wait``
    still steps."""
    poses = pull(np.array([GRASS[0], 0.0, height]), GRASS[1] + 0.15, GRASS[1] - 0.15, speed, 1.0 / 24)
    index = np.concatenate([np.zeros(wait, dtype=int), np.arange(len(poses.position))])
    return ToolPose(poses.position[index], poses.rotation[index])


def test_registry_builds_a_scene_with_the_protocol_at_the_authors_size():
    scene = make_scene("scythe", "planar")
    assert isinstance(scene, Scene) and isinstance(scene, PlanarScytheScene)
    assert (scene.tool, scene.world) == ("scythe", "planar")
    assert [p.name for p in scene.parameters] == ["grass_position"]
    assert (scene.stalk_count, scene.patch_size, scene.stalk_width) == (10, (0.4, 0.1), 0.005)
    with pytest.raises(RuntimeError, match="call reset"):
        scene.goal_reward()
    with pytest.raises(RuntimeError, match="call reset"):
        scene.step(ToolPose(np.zeros(3), np.eye(3)))


@pytest.mark.parametrize(
    "poses",
    [scripted_sweep({"grass_position": GRASS}), pulled(1.3, 0.05), pulled(2.0, 0.15), pulled(0.8, 0.05)],
    ids=["scripted", "slow pull", "high pull", "too slow"],
)
def test_the_twin_cuts_what_the_3d_scene_cuts(poses):
    """Same stalks (same draws), same rule on the same 3D motion: the same cuts and success."""
    planar, spatial = PlanarScytheScene(), SpatialScytheScene()
    run(planar, poses, batch_size=3)
    run(spatial, poses, batch_size=3)
    np.testing.assert_array_equal(planar.stalks, spatial.stalks_xy)
    np.testing.assert_array_equal(planar.cut, spatial.cut)
    np.testing.assert_array_equal(planar.is_success(), spatial.is_success())


def test_scripted_pulls_cut_every_stalk_and_slow_or_high_ones_none():
    scene = PlanarScytheScene()
    run(scene, scripted_sweep({"grass_position": GRASS}))
    np.testing.assert_array_equal(scene.goal_reward(), [scene.stalk_count] * 2)
    assert scene.is_success().all()
    for poses in (pulled(0.8, 0.05), pulled(2.0, 0.15)):
        run(scene, poses)
        np.testing.assert_array_equal(scene.goal_reward(), [0.0, 0.0])
        assert np.all((scene.dense_reward() > 0.0) & (scene.dense_reward() <= 0.1))  # shaping without cuts


def test_dense_reward_grows_as_the_head_point_approaches_the_patch_centre_in_the_x_y_plane():
    """0.1 exp(-5 d^2), d the x-y distance from the head point (the authors' tip) to the patch's
    centre (their one grass patch); the height is ignored (the plane's normal), the reward 0 before
    the first step."""
    scene = PlanarScytheScene()
    scene.reset({"grass_position": GRASS}, np.random.default_rng(0), batch_size=2)
    np.testing.assert_array_equal(scene.dense_reward(), [0.0, 0.0])  # no scythe yet
    rewards = []
    for offset in ([-1.5, 0.5, 0.3], [-0.5, 0.2, 0.6], [0.0, 0.0, 0.05]):
        root = GRASS + np.array(offset)
        scene.step(tool_poses(root, root + np.array([0.0, 0.0, 1.0])))
        expected = 0.1 * np.exp(-5.0 * np.sum((GRASS[:2] - root[:2]) ** 2))
        np.testing.assert_allclose(scene.dense_reward(), [expected, expected], rtol=1e-12)
        rewards.append(scene.dense_reward())
    far, near, centre = rewards
    assert np.all((far > 0.0) & (far < near) & (near < centre) & (centre <= 0.1))


def test_same_seed_same_stalks_and_instances_differ():
    first, second = PlanarScytheScene(), PlanarScytheScene()
    first.reset({"grass_position": GRASS}, np.random.default_rng(3), 2)
    second.reset({"grass_position": GRASS}, np.random.default_rng(3), 2)
    np.testing.assert_array_equal(first.stalks, second.stalks)
    assert not np.allclose(first.stalks[0], first.stalks[1])
    assert np.all(np.abs(first.stalks - GRASS[:2]) <= np.array(first.patch_size) / 2)


def test_success_needs_the_cut_within_the_window():
    scene = PlanarScytheScene()
    run(scene, pulled(2.0, 0.05, wait=30))  # the pull starts after 1.25 s
    assert scene.goal_reward().sum() > 0 and not scene.is_success().any()


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
    np.testing.assert_allclose(scene.footprints({"grass_position": GRASS}), [[1.0, 0.5, 0.2, 0.05, 0.0]])
    snapshot = scene.snapshot()
    assert snapshot["stalks"].shape == (scene.stalk_count, 3) and not snapshot["cut"].any()
    scene.step(ToolPose(np.array([0.0, 0.0, 0.05]), LEVEL))
    np.testing.assert_allclose(scene.snapshot()["blade"], [[0.02, -0.02, 0.05], [0.37, -0.02, 0.05]], atol=1e-12)


def test_per_instance_patches_put_each_instance_s_stalks_in_its_own_patch():
    """Instance 1's patch stands 1 m further along x: its stalks are there, the pull across
    instance 0's patch cuts only instance 0's, and the dense term measures each from its own patch."""
    scene = PlanarScytheScene()
    patches = np.stack([GRASS, GRASS + np.array([1.0, 0.0, 0.0])])
    scene.reset({"grass_position": patches}, np.random.default_rng(0), batch_size=2)
    half = np.array(scene.patch_size) / 2
    assert np.all(np.abs(scene.stalks - patches[:, None, :2]) <= half)
    for position, rotation in zip(*pulled(1.3, 0.05)):
        scene.step(ToolPose(position, rotation))
    assert scene.goal_reward()[0] > 0 and scene.goal_reward()[1] == 0
    dense = scene.dense_reward()
    assert dense[0] > dense[1] > 0.0
