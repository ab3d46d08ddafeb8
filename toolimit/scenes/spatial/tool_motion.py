"""Kinematic tool motion between control steps, shared by the 3D scenes.

A scene's ``step`` receives the tool pose at the end of a control step; between the previous and
the new pose the tool moves at constant linear and angular velocity (straight line for the head
point, geodesic for the rotation). Scenes sub-step this motion so that fast strikes and sweeps are
tested for contact along their path, not only at the control instants.
"""

from __future__ import annotations

import numpy as np

from toolimit.rotations import rotation_matrices, rotation_vectors
from toolimit.scenes.base import batched_pose
from toolimit.tools import ToolPose


def interpolate_poses(
    start_position: np.ndarray,
    start_rotation: np.ndarray,
    end_position: np.ndarray,
    end_rotation: np.ndarray,
    fractions: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Poses at ``fractions`` (S,) in [0, 1] of the constant-velocity motion from start to end.

    Positions (B, 3) in metres, rotations (B, 3, 3) world-from-tool. Returns (S, B, 3) positions
    and (S, B, 3, 3) rotations: ``R(f) = R0 exp(f log(R0^T R1))``.
    """
    fractions = np.asarray(fractions, dtype=float)
    relative = np.swapaxes(start_rotation, -1, -2) @ end_rotation
    rotvec = rotation_vectors(relative)  # (B, 3), tool frame
    steps = rotation_matrices(fractions[:, None, None] * rotvec[None])  # (S, B, 3, 3)
    rotations = start_rotation[None] @ steps
    positions = start_position[None] + fractions[:, None, None] * (end_position - start_position)[None]
    return positions, rotations


def tool_snapshot(position: np.ndarray | None, rotation: np.ndarray | None) -> dict[str, np.ndarray]:
    """Instance 0's tool pose for a scene snapshot: ``tool_position`` (3,) m and ``tool_rotation``
    (3, 3) world-from-tool, from (B, 3) and (B, 3, 3); NaN before the tool's first step (None)."""
    if position is None or rotation is None:
        return {"tool_position": np.full(3, np.nan), "tool_rotation": np.full((3, 3), np.nan)}
    return {"tool_position": position[0].copy(), "tool_rotation": rotation[0].copy()}


class SweptTool:
    """B copies of a kinematic tool: its pose at the end of the last control step and its motion
    to the next one (constant velocity, see the module docstring). The tool is absent (pose None)
    until the first step after ``reset`` places it."""

    def __init__(self, batch_size: int) -> None:
        self.batch_size = batch_size
        self.position: np.ndarray | None = None  # (B, 3) world, m
        self.rotation: np.ndarray | None = None  # (B, 3, 3) world-from-tool

    def move(self, tool_pose: ToolPose, substeps: int) -> tuple[np.ndarray, np.ndarray] | None:
        """Move to ``tool_pose`` ((3,)/(3, 3) or (B, 3)/(B, 3, 3)); returns the poses at the S + 1
        instants ``k / substeps`` of the motion from the last pose ((S+1, B, 3) m and
        (S+1, B, 3, 3)), or None when this step places the tool."""
        position, rotation = batched_pose(tool_pose, self.batch_size)
        start_position, start_rotation = self.position, self.rotation
        self.position, self.rotation = position, rotation
        if start_position is None or start_rotation is None:
            return None
        fractions = np.arange(substeps + 1) / substeps
        return interpolate_poses(start_position, start_rotation, position, rotation, fractions)
