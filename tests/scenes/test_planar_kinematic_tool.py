"""The kinematic tool driver of the planar scenes: plane mapping, placement, velocities, outlines."""

from __future__ import annotations

import numpy as np
import pymunk
import pytest

from toolimit.scenes.base import batched_pose
from toolimit.scenes.planar.kinematic_tool import KinematicTool, to_plane
from toolimit.tools import ToolPose, tool_poses


def test_plane_mapping_drops_the_normal_coordinate():
    point = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(to_plane(point, "xz"), [1.0, 3.0])
    np.testing.assert_allclose(to_plane(point, "xy"), [1.0, 2.0])


def test_batched_pose_broadcasts_and_rejects_bad_input():
    position, rotation = batched_pose(ToolPose(np.zeros(3), np.eye(3)), 4)
    assert position.shape == (4, 3) and rotation.shape == (4, 3, 3)
    with pytest.raises(ValueError, match=r"\(3,\) or \(4, 3\)"):
        batched_pose(ToolPose(np.zeros((2, 3)), np.eye(3)), 4)
    with pytest.raises(ValueError, match="non-finite"):
        batched_pose(ToolPose(np.array([0.0, np.nan, 0.0]), np.eye(3)), 4)


def _pose(head_x: float, head_z: float, handle_angle: float) -> ToolPose:
    """Tool in the x-z plane, head at (x, z), handle direction at ``handle_angle`` from +x (rad)."""
    head = np.array([head_x, 0.0, head_z])
    return tool_poses(head, head + 0.4 * np.array([np.cos(handle_angle), 0.0, np.sin(handle_angle)]))


def test_first_step_places_at_rest_then_velocity_reaches_the_target():
    spaces = [pymunk.Space(), pymunk.Space()]
    tool = KinematicTool(spaces, "xz", reference_axis=2)
    dt = 1.0 / 24.0
    tool.begin_step(_pose(0.1, 0.2, 0.0), dt)
    assert all(tuple(body.velocity) == (0.0, 0.0) and body.angular_velocity == 0.0 for body in tool.bodies)
    np.testing.assert_allclose(tuple(tool.bodies[0].position), (0.1, 0.2))
    tool.end_step()

    tool.begin_step(_pose(0.2, 0.1, 0.3), dt)
    np.testing.assert_allclose(tuple(tool.bodies[1].velocity), (0.1 / dt, -0.1 / dt))
    assert tool.bodies[1].angular_velocity == pytest.approx(0.3 / dt)
    for space in spaces:
        for _ in range(10):
            space.step(dt / 10)
    # pymunk's own integration of the velocities lands on the target (before any snapping)
    np.testing.assert_allclose(tuple(tool.bodies[0].position), (0.2, 0.1), atol=1e-9)
    assert tool.bodies[0].angle == pytest.approx(0.3)
    tool.end_step()


def test_angle_wraps_across_pi_instead_of_spinning_back():
    tool = KinematicTool([pymunk.Space()], "xz", reference_axis=2)
    tool.begin_step(_pose(0.0, 0.0, np.pi - 0.05), 0.1)
    tool.end_step()
    tool.begin_step(_pose(0.0, 0.0, -np.pi + 0.05), 0.1)
    assert tool.bodies[0].angular_velocity == pytest.approx(0.1 / 0.1)


def test_outline_is_the_projection_of_the_tool_frame_points():
    """A point along tool x keeps its length when x lies in the plane and vanishes when it is normal."""
    tool = KinematicTool([pymunk.Space(), pymunk.Space()], "xz", reference_axis=2)
    head = np.zeros((2, 3))
    handle = np.array([[-0.4, 0.0, 0.0], [-0.4, 0.0, 0.0]])
    tool.begin_step(tool_poses(head, handle, np.array([0.0, np.pi / 2])), 1.0 / 24.0)
    local = tool.local_points(np.array([[0.05, 0.0, 0.0], [0.0, 0.0, 0.22]]))
    assert np.linalg.norm(local[0, 0]) == pytest.approx(0.05)
    assert np.linalg.norm(local[1, 0]) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(local[:, 1], [[0.22, 0.0], [0.22, 0.0]], atol=1e-12)  # blade along body x
