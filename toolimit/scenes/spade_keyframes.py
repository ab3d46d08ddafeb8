"""Spade motions through keyframes: the one pose rule of the planar and the 3D scripted scoops.

A keyframe is (time s, head position (3,) m, handle elevation rad), world frame. Between keyframes
the head (the blade tip) moves along a straight line and the elevation changes linearly. The
spade's axis (tool z, tip towards handle) stays in the vertical plane of ``heading``, a horizontal
unit vector from the tip towards the handle, raised by the elevation (positive: handle up,
negative: tip up); the blade's face normal (tool x) is that axis turned by +90 degrees in the same
plane, so that at elevation 0 the face looks up and carries sand (toolimit's tool frame,
:mod:`toolimit.tools`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from toolimit.tools import ToolPose

#: One keyframe: time (s), head position (3,) m, handle elevation (rad).
Keyframe = tuple[float, np.ndarray, float]


def spade_keyframe_motion(keyframes: Sequence[Keyframe], heading: np.ndarray, fps: float) -> ToolPose:
    """(T, 3) head positions and (T, 3, 3) rotations (world frame) sampled at ``fps`` from time 0 to
    the last keyframe's time, through ``keyframes`` (ascending times) along ``heading`` (3,)."""
    key_times = np.array([k[0] for k in keyframes], dtype=float)
    if len(key_times) < 2 or np.any(np.diff(key_times) <= 0):
        raise ValueError(f"keyframe times must be at least two, strictly increasing, got {key_times.tolist()}")
    key_heads = np.array([np.asarray(k[1], dtype=float) for k in keyframes])
    times = np.arange(0.0, key_times[-1] + 1e-9, 1.0 / fps)
    heads = np.stack([np.interp(times, key_times, key_heads[:, a]) for a in range(3)], axis=-1)
    elevation = np.interp(times, key_times, [k[2] for k in keyframes])
    heading = np.asarray(heading, dtype=float)
    up = np.array([0.0, 0.0, 1.0])
    axis = np.cos(elevation)[:, None] * heading + np.sin(elevation)[:, None] * up  # tool z
    face = -np.sin(elevation)[:, None] * heading + np.cos(elevation)[:, None] * up  # tool x, face normal
    rotations = np.stack([face, np.cross(axis, face), axis], axis=-1)
    return ToolPose(heads, rotations)
