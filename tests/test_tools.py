import numpy as np
import pytest

from toolimit.errors import InputError
from toolimit.tools import ToolPose, hold_last, roll_of, rotation_z, swing_rotation, tool_poses, tool_spec


def test_swing_rotation_is_a_rotation_taking_z_to_axis():
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(200, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    axes[0] = [0, 0, -1]
    axes[1] = [0, 0, 1]
    rot = swing_rotation(axes)
    assert np.allclose(rot @ np.swapaxes(rot, 1, 2), np.eye(3), atol=1e-9)
    assert np.allclose(np.linalg.det(rot), 1.0)
    assert np.allclose(rot[:, :, 2], axes, atol=1e-9)


def test_roll_round_trip():
    rng = np.random.default_rng(1)
    head = rng.normal(size=(50, 3))
    handle = head + rng.normal(size=(50, 3))
    roll = rng.uniform(-np.pi, np.pi, 50)
    pose = tool_poses(head, handle, roll)
    assert np.allclose(roll_of(pose.rotation), roll, atol=1e-9)
    axis = (handle - head) / np.linalg.norm(handle - head, axis=1, keepdims=True)
    assert np.allclose(pose.rotation[:, :, 2], axis)


def test_unknown_tool_is_named():
    with pytest.raises(ValueError, match="unknown tool 'rake'"):
        tool_spec("rake")


def test_hold_last_repeats_the_last_pose_and_refuses_a_negative_count():
    poses = ToolPose(np.arange(6.0).reshape(2, 3), np.stack([np.eye(3), rotation_z(0.3)]))
    held = hold_last(poses, 3)
    assert held.position.shape == (5, 3) and held.rotation.shape == (5, 3, 3)
    np.testing.assert_array_equal(held.position[:2], poses.position)
    np.testing.assert_array_equal(held.position[2:], np.repeat(poses.position[-1:], 3, axis=0))
    np.testing.assert_array_equal(held.rotation[4], rotation_z(0.3))
    with pytest.raises(InputError, match="steps to hold must be >= 0, got -1"):
        hold_last(poses, -1)
