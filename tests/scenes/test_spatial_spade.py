"""The 3D spade world: protocol, parameters, heap at rest, scripted scoop, rewards, determinism."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from toolimit.scenes import InvalidSceneParameters, Scene, make_scene
from toolimit.scenes.base import WORLD_HALF_SIZE
from toolimit.scenes.spatial.particles import GranularMaterial
from toolimit.scenes.spatial.scoop import scripted_scoop
from toolimit.scenes.spatial.spade import (
    AUTHORS_SAND,
    DEPOSIT_INNER,
    DEPOSIT_WALL_HEIGHT,
    GOAL_INNER,
    MAX_SPHERES,
    SpatialSpadeScene,
    settled_heap,
)
from toolimit.tools import ToolPose

PARAMS = {"sand_position": np.array([1.0, -0.5, 0.0]), "sand_yaw": 2.2, "goal_position": np.array([0.2, 0.3, 0.0])}
FAR_AWAY = ToolPose(np.array([3.0, 3.0, 1.0]), np.eye(3))


def deposit_frame(points: np.ndarray, params=PARAMS) -> np.ndarray:
    """World points (..., 3) in the deposit's frame (origin at its floor centre, turned by sand_yaw)."""
    c, s = np.cos(params["sand_yaw"]), np.sin(params["sand_yaw"])
    rotation = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    return (points - params["sand_position"]) @ rotation


def run_scoop(scene: SpatialSpadeScene, seed: int, batch_size: int) -> None:
    scene.reset(PARAMS, np.random.default_rng(seed), batch_size)
    motion = scripted_scoop(PARAMS)
    for position, rotation in zip(motion.position, motion.rotation):
        scene.step(ToolPose(position, rotation))
        assert np.all(scene.static_penetration() <= 1e-3), "no sphere 1 mm into the ground or a wall"


@pytest.fixture(scope="module")
def scooped() -> SpatialSpadeScene:
    """B = 2 instances after the scripted scoop-carry-tip motion (seed 0)."""
    scene = SpatialSpadeScene()
    run_scoop(scene, seed=0, batch_size=2)
    return scene


def test_registry_builds_the_scene_and_it_follows_the_protocol() -> None:
    scene = make_scene("spade", "3d", n_spheres=40)
    assert isinstance(scene, SpatialSpadeScene) and isinstance(scene, Scene)
    assert (scene.tool, scene.world, scene.n_spheres) == ("spade", "3d", 40)
    assert scene.control_dt == pytest.approx(1 / 24)
    kinds = {p.name: (p.kind, p.on_ground) for p in scene.parameters}
    assert kinds == {"sand_position": ("position", True), "sand_yaw": ("uniform", True),
                     "goal_position": ("position", True)}
    assert SpatialSpadeScene().n_spheres == 200, "the original scene's 200 spheres are the default"
    with pytest.raises(ValueError, match="n_spheres"):
        SpatialSpadeScene(n_spheres=MAX_SPHERES + 1)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"goal_position": np.array([1.3, -0.4, 0.0])}, "overlap"),
        ({"goal_position": np.array([6.0, 0.0, 0.0])}, "world bound"),
        ({"sand_yaw": 4.0}, "sand_yaw"),
        ({"sand_position": np.array([1.0, 2.0])}, "sand_position"),
    ],
)
def test_invalid_parameters_are_rejected_with_a_reason(change: dict, message: str) -> None:
    scene = SpatialSpadeScene()
    params = {**PARAMS, **change}
    assert message in scene.invalid_reason(params)
    with pytest.raises(InvalidSceneParameters, match=message):
        scene.reset(params, np.random.default_rng(0))
    assert scene.invalid_reason(PARAMS) is None
    assert "missing" in scene.invalid_reason({"sand_yaw": 0.0})
    # Just apart: rectangles 0.42 m and 0.52 m wide whose centres are 0.48 m apart along x are valid.
    touching = {"sand_position": np.zeros(3), "sand_yaw": 0.0, "goal_position": np.array([0.48, 0.0, 0.0])}
    assert scene.invalid_reason(touching) is None
    beyond = {**PARAMS, "sand_position": np.array([WORLD_HALF_SIZE + 0.01, 0.0, 0.0])}
    assert "world bound" in scene.invalid_reason(beyond)


@pytest.mark.parametrize("freeze_after", [24, None], ids=["island-sleeping", "sleeping-only"])
def test_reset_builds_a_settled_pile_inside_the_deposit_that_stays_at_rest(freeze_after: int | None) -> None:
    scene = SpatialSpadeScene(n_spheres=50, material=GranularMaterial(freeze_after_substeps=freeze_after))
    scene.reset(PARAMS, np.random.default_rng(1), batch_size=2)
    start = scene.snapshot()["sphere_positions"]
    local = deposit_frame(start)
    # This sand rolls more than the authors': falling onto the heap, a few spheres leave by the open
    # side or jump a wall (the authors' sand: the test below).
    assert np.mean(np.all(np.abs(local[:, :2]) < DEPOSIT_INNER / 2, axis=1)) > 0.8
    assert np.all(scene.static_penetration() <= 1e-3)
    assert np.all(local[:, 2] < 0.15)
    assert np.all(scene.goal_reward() == 0)
    for _ in range(48):
        scene.step(FAR_AWAY)
    assert np.max(np.abs(scene.snapshot()["sphere_positions"] - start)) < 1e-4, "the pile must stay at rest"


def test_the_authors_heap_of_200_lies_in_the_deposit_and_stays_there_with_no_tool() -> None:
    """Settled in the deposit's own walls (as the original), the 200-sphere heap is at rest at reset:
    over 150 steps no sphere moves 1 mm (a heap settled elsewhere slumps: a 0.36 m pen's moved
    73 mm, benchmarks/heap_settle.py). At most 2 spheres lie past the open side, none beyond a wall."""
    scene = SpatialSpadeScene()
    scene.reset(PARAMS, np.random.default_rng(0), batch_size=2)
    start = scene.sphere_positions
    local = deposit_frame(start[0])
    half = DEPOSIT_INNER / 2
    assert np.all(np.abs(local[:, 0]) < half) and np.all(local[:, 1] > -half), "none beyond a wall"
    assert np.sum(local[:, 1] > half) <= 2, "out of the open side"
    assert np.sum(local[:, 2] > DEPOSIT_WALL_HEIGHT) > 20, "a heap, not a layer"
    for _ in range(150):
        scene.step(FAR_AWAY)
    moved = np.linalg.norm(scene.sphere_positions - start, axis=-1)
    assert moved.max() < 1e-3, f"a sphere moved {1000 * moved.max():.1f} mm"


def test_the_heap_is_placed_and_turned_with_the_deposit() -> None:
    """In the deposit's frame every instance's heap is the cached one, whatever the deposit's pose."""
    heap = settled_heap(200, AUTHORS_SAND, 10)
    for params in (PARAMS, {**PARAMS, "sand_yaw": -0.4, "sand_position": np.array([-1.0, 2.0, 0.0])}):
        scene = SpatialSpadeScene()
        scene.reset(params, np.random.default_rng(0), batch_size=2)
        for instance in scene.sphere_positions:
            np.testing.assert_allclose(deposit_frame(instance, params), heap, atol=1e-12)


def test_first_step_places_the_tool_without_velocity() -> None:
    """A spade that appears inside the pile moves spheres out of it without flinging the pile.

    The placement's 20 position passes leave some overlaps in a packed heap, which the first step
    resolves with velocity: at this pose 3 of the 200 spheres reach the 1 m/s cap (with the former
    pen-settled heap none passed 0.5 m/s here, but 1-6 did at 6 of 15 neighbouring poses,
    the heap's measurement, benchmarks/heap_settle.py), so the check bounds how many are fast, not the fastest."""
    scene = SpatialSpadeScene()
    scene.reset(PARAMS, np.random.default_rng(2))
    pose = scripted_scoop(PARAMS)
    inside = ToolPose(PARAMS["sand_position"] + np.array([0.0, 0.0, 0.01]), pose.rotation[30])
    scene.step(inside)
    speeds = np.linalg.norm(scene.sphere_velocities, axis=-1)
    assert np.sum(speeds > 0.5) <= 5, f"{np.sum(speeds > 0.5)} spheres were flung faster than 0.5 m/s"
    assert np.median(speeds[speeds > 0]) < 0.2
    assert scene.snapshot()["sphere_positions"][:, 2].max() < 0.3


def test_step_broadcasts_one_pose_and_accepts_per_instance_poses() -> None:
    scene = SpatialSpadeScene()
    scene.reset(PARAMS, np.random.default_rng(0), batch_size=3)
    motion = scripted_scoop(PARAMS)
    scene.step(ToolPose(motion.position[0], motion.rotation[0]))
    scene.step(ToolPose(np.repeat(motion.position[1][None], 3, 0), np.repeat(motion.rotation[1][None], 3, 0)))
    assert scene.tool_pose.position.shape == (3, 3)
    with pytest.raises(ValueError, match="shape"):
        scene.step(ToolPose(np.zeros((2, 3)), np.repeat(np.eye(3)[None], 2, 0)))


def test_scripted_scoop_carry_tip_moves_at_least_ten_spheres_into_the_box(scooped: SpatialSpadeScene) -> None:
    rewards = scooped.goal_reward()
    assert rewards.shape == (2,)
    assert np.all(rewards >= 10), rewards
    snap = scooped.snapshot()
    offset = snap["sphere_positions"] - PARAMS["goal_position"]
    in_box = (np.abs(offset[:, :2]).max(axis=1) < GOAL_INNER / 2) & (offset[:, 2] <= 0.1)
    assert in_box.sum() == rewards[0]
    assert np.array_equal(rewards, scooped.spheres_in_box().sum(axis=1))  # the compiled count, the array test


def test_success_needs_ten_spheres_for_half_of_the_steps(scooped: SpatialSpadeScene) -> None:
    scooped = copy.deepcopy(scooped)  # the module's fixture stays as the motion left it
    assert not np.any(scooped.is_success()), "the spheres arrived late in the motion"
    steps = scooped.success_tracker.steps
    for _ in range(steps):
        scooped.step(scooped.tool_pose)
        if np.all(scooped.is_success()):
            break
    assert np.all(scooped.is_success())
    assert scooped.success_tracker.successful_steps[0] >= scooped.success_tracker.steps / 2


def appendix_spade_reward(scene: SpatialSpadeScene, tool_pose: ToolPose | None) -> np.ndarray:
    """(B,) the authors' dense spade reward written out: mean over spheres of exp(-5 |c - g|^2), g the
    box's floor centre, + 0.05 exp(-5 |handle end - deposit floor centre|^2) once placed (the handle
    end 0.40 m up the tool's z from the blade tip: their spade body's origin)."""
    goal = PARAMS["goal_position"]
    reward = np.exp(-5.0 * np.sum((scene.sphere_positions - goal) ** 2, axis=-1)).mean(axis=1)
    if tool_pose is not None:
        handle_end = tool_pose.position + 0.40 * tool_pose.rotation[..., :, 2]
        reward += 0.05 * np.exp(-5.0 * np.sum((handle_end - PARAMS["sand_position"]) ** 2, axis=-1))
    return reward


def test_dense_reward_before_the_first_step_is_the_sand_term_alone() -> None:
    scene = SpatialSpadeScene()
    scene.reset(PARAMS, np.random.default_rng(0), batch_size=2)
    dense = scene.dense_reward()
    np.testing.assert_allclose(dense, appendix_spade_reward(scene, None), rtol=1e-12)
    assert np.all((dense > 0.0) & (dense < 0.01)), "the sand is about 1.1 m from the box"


def test_dense_reward_adds_the_tool_term_for_the_handle_end_near_the_deposit() -> None:
    """Instance 0's tip 0.5 m above the deposit's floor centre, its handle end 0.9 m (term
    0.05 exp(-4.05)), instance 1's far away (term ~0); neither touches the sand."""
    scene = SpatialSpadeScene()
    scene.reset(PARAMS, np.random.default_rng(0), batch_size=2)
    above = PARAMS["sand_position"] + np.array([0.0, 0.0, 0.5])
    tips = np.stack([above, FAR_AWAY.position])
    pose = ToolPose(tips, np.repeat(np.eye(3)[None], 2, 0))
    scene.step(pose)
    dense = scene.dense_reward()
    np.testing.assert_allclose(dense, appendix_spade_reward(scene, pose), rtol=1e-12)
    tool_term = dense - appendix_spade_reward(scene, None)
    assert tool_term == pytest.approx([0.05 * np.exp(-5.0 * 0.9**2), 0.0], abs=1e-9)


def test_dense_reward_rises_with_the_sand_moved_into_the_box(scooped: SpatialSpadeScene) -> None:
    """The scooped instances against unscooped ones with the spade at the same pose (same tool term)."""
    dense = scooped.dense_reward()
    np.testing.assert_allclose(dense, appendix_spade_reward(scooped, scooped.tool_pose), rtol=1e-12)
    assert np.all((dense >= 0.0) & (dense <= 1.05))
    unscooped = SpatialSpadeScene()
    unscooped.reset(PARAMS, np.random.default_rng(0), batch_size=2)
    unscooped.step(scooped.tool_pose)  # placed over the box, away from the sand
    # A sphere anywhere in the box region is within d^2 = 0.13 m^2 of g (term >= exp(-0.65) = 0.52),
    # in the deposit at least 0.85 m from it (term <= 0.03): each one moved adds >= 0.4 / N.
    rise = dense - unscooped.dense_reward()
    assert np.all(rise > 0.4 * scooped.goal_reward() / scooped.n_spheres), rise


def test_rollouts_repeat_whatever_the_seed_and_instances_differ_by_their_parameters() -> None:
    """The scene has no randomness of its own (the heap is the cached one); instances whose deposits
    stand apart (the learner's reset noise) stir their sand differently under the same motion."""
    motion = scripted_scoop(PARAMS)
    shifted = {**PARAMS, "sand_position": PARAMS["sand_position"] + np.array([[0.0, 0.0, 0.0], [0.01, -0.01, 0.0]])}
    scenes = []
    for params, seed in ((PARAMS, 5), (PARAMS, 6), (shifted, 5)):
        scene = SpatialSpadeScene()
        scene.reset(params, np.random.default_rng(seed), batch_size=2)
        for k in range(40):
            scene.step(ToolPose(motion.position[k], motion.rotation[k]))
        scenes.append(scene.sphere_positions)
    np.testing.assert_array_equal(scenes[0], scenes[1])
    np.testing.assert_array_equal(scenes[0][0], scenes[0][1])
    np.testing.assert_array_equal(scenes[2][0], scenes[0][0])
    moved_with_deposit = scenes[2][1] - np.array([0.01, -0.01, 0.0])
    assert not np.allclose(moved_with_deposit, scenes[0][1], atol=1e-3), "the same sand under another blade path"


def test_footprints_and_snapshot_describe_instance_zero(scooped: SpatialSpadeScene) -> None:
    footprints = scooped.footprints(PARAMS)
    assert footprints.shape == (2, 5)
    np.testing.assert_allclose(footprints[0], [1.0, -0.5, 0.21, 0.21, 2.2])
    np.testing.assert_allclose(footprints[1], [0.2, 0.3, 0.26, 0.26, 0.0])
    snap = scooped.snapshot()
    assert snap["sphere_positions"].shape == (200, 3)
    assert snap["wall_centers"].shape == (7, 3) and snap["wall_rotations"].shape == (7, 3, 3)
    assert snap["tool_rotation"].shape == (3, 3) and np.all(np.isfinite(snap["tool_position"]))
    assert float(snap["in_box"]) == scooped.goal_reward()[0]
    fresh = SpatialSpadeScene()
    with pytest.raises(RuntimeError, match="reset"):
        fresh.goal_reward()
    fresh.reset(PARAMS, np.random.default_rng(0))
    assert np.all(np.isnan(fresh.snapshot()["tool_position"]))
