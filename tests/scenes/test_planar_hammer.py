"""Planar hammer scene: momentum transfer, planting, misses, tunnelling, parameters, success window."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.scenes import InvalidSceneParameters, Scene, make_scene
from toolimit.scenes.planar.hammer import PlanarHammerScene
from toolimit.tools import ToolPose, tool_poses

FPS = 24.0
NAIL = np.array([0.5, 0.0, 0.3])
FACE_OFFSET = 0.055  # head centre to striking face along tool x (half of ToolSpec.head_width), m


def strike(speed: float, overshoot: float, dx: float = 0.0, wait: int = 3, rest: int = 6) -> ToolPose:
    """A vertical strike at ``speed`` m/s whose face ends ``overshoot`` m below the nail's top.

    The handle points to +x, so tool x (the face) points down. The head waits ``wait`` frames, falls
    for three frames at constant speed (the contact happens mid-frame at full speed), then stops.
    """
    top = NAIL[2] + FACE_OFFSET
    zs = top - overshoot + speed / FPS * np.arange(3, -1, -1)
    zs = np.concatenate([np.full(wait, zs[0]), zs, np.full(rest, zs[-1])])
    head = np.stack([np.full_like(zs, NAIL[0] + dx), np.zeros_like(zs), zs], axis=1)
    return tool_poses(head, head + np.array([0.33, 0.0, 0.0]))


def run(scene: PlanarHammerScene, poses: ToolPose, batch_size: int = 1) -> None:
    scene.reset({"nail_position": NAIL}, np.random.default_rng(0), batch_size)
    for position, rotation in zip(poses.position, poses.rotation):
        scene.step(ToolPose(position, rotation))


def test_registry_builds_a_scene_with_the_protocol():
    scene = make_scene("hammer", "planar")
    assert isinstance(scene, Scene) and isinstance(scene, PlanarHammerScene)
    assert (scene.tool, scene.world, scene.control_dt) == ("hammer", "planar", pytest.approx(1 / 24))
    (nail,) = scene.parameters
    assert nail.name == "nail_position" and nail.kind == "position" and not nail.on_ground
    with pytest.raises(RuntimeError, match="call reset"):
        scene.goal_reward()
    with pytest.raises(RuntimeError, match="call reset"):
        scene.step(ToolPose(np.zeros(3), np.eye(3)))


def test_nail_rests_without_a_tool():
    scene = PlanarHammerScene()
    scene.reset({"nail_position": NAIL}, np.random.default_rng(0))
    dt = scene.control_dt / scene.substeps
    for _ in range(int(2.0 / dt)):
        scene._spaces[0].step(dt)
    assert scene.travel()[0] < 1e-6 and scene.goal_reward()[0] == 0


def test_a_strike_drives_the_nail_further_than_a_tap_on_the_same_path():
    """Same path (face 5 mm below the nail top): a 0.3 m/s tap pushes the nail ~5 mm; a 3 m/s strike
    hands it its momentum and the nail slides on against the entry friction, about 1 cm more."""
    tap, full = PlanarHammerScene(), PlanarHammerScene()
    run(tap, strike(0.3, 0.005))
    run(full, strike(3.0, 0.005))
    assert 0.003 < tap.travel()[0] < 0.007
    assert full.travel()[0] > tap.travel()[0] + 0.006
    assert full.travel()[0] < 0.03
    assert tap.goal_reward()[0] == full.goal_reward()[0] == 0


def test_a_deep_strike_plants_the_nail_within_the_window():
    scene = PlanarHammerScene()
    run(scene, strike(3.0, 0.06), batch_size=2)
    np.testing.assert_array_equal(scene.goal_reward(), [1.0, 1.0])
    assert scene.travel() == pytest.approx([0.05, 0.05])
    assert scene.is_success().all()
    # The face rests 60 mm below the nail's start, the planted nail's head centre 50 mm + half the
    # head's thickness below it: the dense reward measures the distance between the two.
    distance = 0.01 - scene.nail_head_thickness / 2
    assert scene.dense_reward() == pytest.approx(np.exp(-5.0 * distance**2))

    late = PlanarHammerScene(success_window=0.2)  # planted at ~0.25 s: outside a 0.2 s window
    run(late, strike(3.0, 0.06))
    assert late.goal_reward()[0] == 1 and not late.is_success()[0]


def test_dense_reward_grows_as_the_head_approaches_the_nail_in_the_x_z_plane():
    """exp(-5 d^2), d the x-z distance from the striking face (the authors' hammer tip) to the nail
    head's centre (their nail body's origin); the head's y is ignored (the plane's normal), the
    reward 0 before the first step."""
    scene = PlanarHammerScene()
    scene.reset({"nail_position": NAIL}, np.random.default_rng(0))
    assert scene.dense_reward()[0] == 0.0  # no hammer yet
    rewards = []
    for offset in ([0.3, 0.7, 0.4], [0.1, 0.7, 0.2], [0.0, 0.7, 0.1]):
        head = NAIL + np.array(offset)
        scene.step(tool_poses(head, head + np.array([0.33, 0.0, 0.0])))
        face_above_centre = offset[2] - FACE_OFFSET + scene.nail_head_thickness / 2  # tool x points down
        assert scene.dense_reward()[0] == pytest.approx(np.exp(-5.0 * (offset[0] ** 2 + face_above_centre**2)))
        rewards.append(scene.dense_reward()[0])
    assert 0.0 < rewards[0] < rewards[1] < rewards[2] <= 1.0


def test_a_strike_beside_the_nail_does_nothing():
    scene = PlanarHammerScene()
    run(scene, strike(3.0, 0.06, dx=0.06))  # head lands on the board beside the nail
    assert scene.travel()[0] == 0.0 and scene.goal_reward()[0] == 0 and not scene.is_success()[0]


def test_each_instance_follows_its_own_pose():
    """One batch: instance 0 strikes the nail, instance 1 strikes the board beside it."""
    on_nail, beside = strike(3.0, 0.06), strike(3.0, 0.06, dx=0.06)
    scene = PlanarHammerScene()
    scene.reset({"nail_position": NAIL}, np.random.default_rng(0), batch_size=2)
    for t in range(len(on_nail.position)):
        position = np.stack([on_nail.position[t], beside.position[t]])
        rotation = np.stack([on_nail.rotation[t], beside.rotation[t]])
        scene.step(ToolPose(position, rotation))
    np.testing.assert_array_equal(scene.goal_reward(), [1.0, 0.0])
    np.testing.assert_array_equal(scene.is_success(), [True, False])


def test_hammer_at_4_m_s_does_not_pass_through_the_nail():
    """The face may sink into the nail head by at most one sub-step's travel (4 m/s / 480 Hz) while
    it pushes; once the hammer rests the nail's top is below the face, never left above it."""
    scene = PlanarHammerScene()
    poses = strike(4.0, 0.03)
    scene.reset({"nail_position": NAIL}, np.random.default_rng(0))
    substep_travel = 4.0 * scene.control_dt / scene.substeps
    for position, rotation in zip(poses.position, poses.rotation):
        scene.step(ToolPose(position, rotation))
        face = position[2] - FACE_OFFSET
        assert NAIL[2] - scene.travel()[0] <= face + substep_travel
    assert NAIL[2] - scene.travel()[0] <= face + 0.001
    assert scene.goal_reward()[0] == 1  # 30 mm pushed + the slide of a 4 m/s nail


def test_invalid_parameters_are_rejected_with_a_reason():
    scene = PlanarHammerScene()
    low = {"nail_position": np.array([0.0, 0.0, 0.02])}
    assert "below the ground" in scene.invalid_reason(low)
    assert "outside the world" in scene.invalid_reason({"nail_position": np.array([6.0, 0.0, 0.3])})
    assert "finite (3,)" in scene.invalid_reason({"nail_position": np.array([0.0, 0.3])})
    with pytest.raises(InvalidSceneParameters, match="below the ground"):
        scene.reset(low, np.random.default_rng(0))


def test_footprints_and_snapshot():
    scene = PlanarHammerScene()
    scene.reset({"nail_position": NAIL}, np.random.default_rng(0))
    assert scene.footprints({"nail_position": NAIL}).shape == (1, 5)
    snapshot = scene.snapshot()
    np.testing.assert_allclose(snapshot["nail_top"], NAIL)
    assert snapshot["board"][1, 2] == pytest.approx(NAIL[2] - scene.protrusion)
    scene.step(ToolPose(np.array([0.5, 0.0, 0.6]), np.eye(3)))
    assert scene.snapshot()["hammer_head"].shape == (8, 3)


def test_per_instance_nail_positions_put_each_nail_where_its_own_strike_lands():
    """Instance 1's nail stands 0.5 m further along x: the strike over each nail plants that one."""
    scene = PlanarHammerScene()
    nails = np.stack([NAIL, NAIL + np.array([0.5, 0.0, 0.0])])
    for instance, dx in enumerate((0.0, 0.5)):
        scene.reset({"nail_position": nails}, np.random.default_rng(0), batch_size=2)
        for position, rotation in zip(*strike(3.0, 0.06, dx=dx)):
            scene.step(ToolPose(position, rotation))
        np.testing.assert_array_equal(scene.goal_reward(), [instance == 0, instance == 1])
