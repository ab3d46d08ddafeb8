"""The tool frame shared by scenes, robots and trajectory optimisation, and its maths.

The tool frame (one convention for every tool, world and robot):

* origin at the tool **head** point (spade blade tip, hammer head centre, scythe blade root);
* **z** axis along the tool, from the head towards the handle end;
* **x** axis across the tool, the working direction: the spade blade's face normal on the side
  that carries sand, the hammer face's striking direction, the scythe blade's cutting edge;
* y = z cross x.

A demonstration gives only the head and handle points, so the roll about z is unknown. The frame at
roll 0 is the minimal rotation taking world z onto the tool axis; a roll ``alpha`` then turns it
about the tool axis: ``R = R_swing(axis) @ Rz(alpha)``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from toolimit.errors import InputError


class ToolPose(NamedTuple):
    """Poses of the tool frame in the world frame.

    position: (..., 3) head point, metres. rotation: (..., 3, 3) columns are the tool frame's x, y,
    z axes expressed in the world frame. Leading dimensions may be time (T) or batch (B).
    """

    position: np.ndarray
    rotation: np.ndarray


def swing_rotation(axis: np.ndarray) -> np.ndarray:
    """(..., 3, 3) minimal rotations taking world z onto the unit vectors ``axis`` (..., 3).

    Rodrigues' formula for the rotation about z x axis; the antipodal case (axis = -z) uses a
    half-turn about world x.
    """
    axis = np.asarray(axis, dtype=float)
    axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    x, y, z = axis[..., 0], axis[..., 1], axis[..., 2]
    k = 1.0 / np.maximum(1.0 + z, 1e-12)
    rot = np.empty(axis.shape[:-1] + (3, 3))
    rot[..., 0, 0] = 1.0 - k * x * x
    rot[..., 0, 1] = -k * x * y
    rot[..., 0, 2] = x
    rot[..., 1, 0] = -k * x * y
    rot[..., 1, 1] = 1.0 - k * y * y
    rot[..., 1, 2] = y
    rot[..., 2, 0] = -x
    rot[..., 2, 1] = -y
    rot[..., 2, 2] = z
    antipodal = z < -1.0 + 1e-9
    rot[antipodal] = np.diag([1.0, -1.0, -1.0])
    return rot


def wrap_angle(angle: np.ndarray | float) -> np.ndarray:
    """``angle`` (rad) wrapped into [-pi, pi)."""
    return (np.asarray(angle, dtype=float) + np.pi) % (2 * np.pi) - np.pi


def rotation_z(angle: np.ndarray | float) -> np.ndarray:
    """(..., 3, 3) rotations by ``angle`` (rad) about z."""
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    rot = np.zeros(angle.shape + (3, 3))
    rot[..., 0, 0] = c
    rot[..., 0, 1] = -s
    rot[..., 1, 0] = s
    rot[..., 1, 1] = c
    rot[..., 2, 2] = 1.0
    return rot


def tool_poses(head: np.ndarray, handle: np.ndarray, roll: np.ndarray | float = 0.0) -> ToolPose:
    """Tool-frame poses from head and handle points (..., 3) and roll about the axis (rad)."""
    head = np.asarray(head, dtype=float)
    axis = np.asarray(handle, dtype=float) - head
    rotation = swing_rotation(axis) @ rotation_z(np.broadcast_to(roll, head.shape[:-1]))
    return ToolPose(position=head.copy(), rotation=rotation)


def roll_of(rotation: np.ndarray) -> np.ndarray:
    """(...,) roll (rad) of tool-frame rotations (..., 3, 3): the inverse of :func:`tool_poses`."""
    rotation = np.asarray(rotation, dtype=float)
    local = np.swapaxes(swing_rotation(rotation[..., :, 2]), -1, -2) @ rotation
    return np.arctan2(local[..., 1, 0], local[..., 0, 0])


def hold_last(poses: ToolPose, steps: int) -> ToolPose:
    """(T + steps) poses: ``poses`` (T, ...) then their last pose held for ``steps`` more steps (a motion
    whose effect lands after its end, e.g. sand settling in the box, judged over a longer episode)."""
    if steps < 0:
        raise InputError(f"steps to hold must be >= 0, got {steps}")
    return ToolPose(*(np.concatenate([array, np.repeat(array[-1:], steps, axis=0)]) for array in poses))
