"""Kinematic tool motion between control steps, shared by the 3D scenes.

A scene's ``step`` receives the tool pose at the end of a control step; between the previous and
the new pose the tool moves at constant linear and angular velocity (straight line for the head
point, geodesic for the rotation). Scenes sub-step this motion so that fast strikes and sweeps are
tested for contact along their path, not only at the control instants.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


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
    rotvec = Rotation.from_matrix(relative).as_rotvec()  # (B, 3), tool frame
    steps = Rotation.from_rotvec((fractions[:, None, None] * rotvec[None]).reshape(-1, 3)).as_matrix()
    steps = steps.reshape(len(fractions), -1, 3, 3)
    rotations = start_rotation[None] @ steps
    positions = start_position[None] + fractions[:, None, None] * (end_position - start_position)[None]
    return positions, rotations


def tool_snapshot(position: np.ndarray | None, rotation: np.ndarray | None) -> dict[str, np.ndarray]:
    """Instance 0's tool pose for a scene snapshot: ``tool_position`` (3,) m and ``tool_rotation``
    (3, 3) world-from-tool, from (B, 3) and (B, 3, 3); NaN before the tool's first step (None)."""
    if position is None or rotation is None:
        return {"tool_position": np.full(3, np.nan), "tool_rotation": np.full((3, 3), np.nan)}
    return {"tool_position": position[0].copy(), "tool_rotation": rotation[0].copy()}
