"""The tool-alone replay's speed limit (the authors' ToolEnv: 1 m/s and 2 rad/s per world axis)."""

from __future__ import annotations

import numpy as np

from toolimit.rotations import rotation_vectors
from toolimit.scenes.replay import TOOL_SPEED_LIMIT, replay, speed_limited
from toolimit.tools import ToolPose, rotation_z, tool_spec

DT = 1.0 / 24.0


def straight_line(speed: np.ndarray, steps: int = 48) -> ToolPose:
    """A tool pointing up, its head moving at ``speed`` (3,) m/s."""
    positions = np.arange(steps)[:, None] * DT * np.asarray(speed, dtype=float)
    return ToolPose(positions, np.repeat(np.eye(3)[None], steps, axis=0))


def test_a_motion_within_the_limits_is_unchanged():
    poses = straight_line([0.9, -0.5, 0.2])
    limited = speed_limited(poses, DT, steered_offset=0.4)
    np.testing.assert_allclose(limited.position, poses.position, atol=1e-12)
    np.testing.assert_allclose(limited.rotation, poses.rotation, atol=1e-12)


def test_a_tool_faster_than_one_metre_per_second_is_clipped_per_axis_and_lags():
    poses = straight_line([2.0, 0.5, -3.0])
    limited = speed_limited(poses, DT, steered_offset=0.4)
    velocity = np.diff(limited.position, axis=0) / DT
    np.testing.assert_allclose(velocity[:, 0], 1.0, atol=1e-9)  # x clipped to 1 m/s
    np.testing.assert_allclose(velocity[:, 1], 0.5, atol=1e-9)  # y within the limit: unchanged
    np.testing.assert_allclose(velocity[:, 2], -1.0, atol=1e-9)  # z clipped to -1 m/s
    assert limited.position[-1, 0] < poses.position[-1, 0] - 0.9  # lags the 2 m/s target by ~1 m


def test_the_tool_catches_up_with_targets_that_stop():
    poses = straight_line([2.0, 0.0, 0.0], steps=24)
    held = ToolPose(
        np.concatenate([poses.position, np.repeat(poses.position[-1:], 24, axis=0)]),
        np.concatenate([poses.rotation, np.repeat(poses.rotation[-1:], 24, axis=0)]),
    )
    limited = speed_limited(held, DT, steered_offset=0.0)
    assert np.all(np.abs(np.diff(limited.position, axis=0)) <= TOOL_SPEED_LIMIT.linear * DT + 1e-12)
    np.testing.assert_allclose(limited.position[-1], held.position[-1], atol=1e-12)


def test_rotation_is_clipped_to_two_radians_per_second_per_axis_about_the_steered_point():
    steps = 24
    angles = 4.0 * DT * np.arange(steps)  # 4 rad/s about z
    poses = ToolPose(np.zeros((steps, 3)), rotation_z(angles))
    offset = 0.4
    # the steered point lies on the turn's axis (the tool's z): it stays where it is
    limited = speed_limited(poses, DT, steered_offset=offset)
    turns = rotation_vectors(limited.rotation[1:] @ np.transpose(limited.rotation[:-1], (0, 2, 1)))
    np.testing.assert_allclose(turns[:, 2], TOOL_SPEED_LIMIT.angular * DT, atol=1e-9)
    np.testing.assert_allclose(limited.position, 0.0, atol=1e-12)


def test_replay_limits_the_tool_alone_but_not_a_robot():
    """``replay`` steps the scene through the limited poses, ``tool_alone=False`` through the given ones."""

    class Recorder:
        tool = "spade"
        world = "planar"
        control_dt = DT
        parameters = ()
        batch_size = 0

        def reset(self, params, rng, batch_size=1):
            self.batch_size = batch_size
            self.positions = []

        def step(self, tool_pose):
            self.positions.append(np.asarray(tool_pose.position))

        def goal_reward(self):
            return np.zeros(self.batch_size)

    poses = straight_line([3.0, 0.0, 0.0], steps=10)
    scene = Recorder()
    replay(scene, {}, np.random.default_rng(0), poses)
    expected = speed_limited(poses, DT, tool_spec("spade").steered_offset).position
    np.testing.assert_allclose(np.array(scene.positions), expected, atol=1e-12)
    assert np.max(np.diff(np.array(scene.positions)[:, 0])) <= 1.0 * DT + 1e-12
    replay(scene, {}, np.random.default_rng(0), poses, tool_alone=False)
    np.testing.assert_allclose(np.array(scene.positions), poses.position)
