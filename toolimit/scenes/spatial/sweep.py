"""A hand-made scythe sweep for the 3D scythe scene (tests, LfD baseline).

A motion generator, kept apart from the scene it is made for: it reads the grass patch's
parameters and the scythe's geometry, and returns tool poses any scene replay can follow. The
scythe is held level: its blade (tool x, from the head point, the blade root) along the patch's own
x axis, its snath (tool z) straight up, so its cutting direction (tool +y) is the patch's +y axis.
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.base import CONTROL_FPS, SceneParams
from toolimit.tools import ToolPose, hold_last, rotation_z, tool_spec

#: Length of the cutting edge along tool x from the head point, m.
BLADE_LENGTH = tool_spec("scythe").head_width


def straight_sweep(
    patch_position: np.ndarray,
    patch_yaw: float,
    speed: float,
    height: float,
    dt: float,
    direction: float = 1.0,
    reach: float = 0.4,
) -> ToolPose:
    """Poses every ``dt`` s of the level blade swept straight across the patch at ``patch_position``
    (3,) m turned by ``patch_yaw`` rad: the edge spans the patch's x around its centre, ``height`` m
    above the ground, and moves along the patch's y at ``speed`` m/s from ``-direction * reach`` to
    at least ``+direction * reach`` m (``direction`` -1: backwards, against the cutting direction)."""
    steps = int(np.ceil(2 * reach / (speed * dt)))
    along = direction * (-reach + speed * dt * np.arange(steps + 1))
    local = np.column_stack([np.full(steps + 1, -BLADE_LENGTH / 2), along, np.full(steps + 1, height)])
    turn = rotation_z(patch_yaw)
    centre = np.asarray(patch_position, dtype=float) * np.array([1.0, 1.0, 0.0])
    return ToolPose(centre + local @ turn.T, np.repeat(turn[None], steps + 1, axis=0))


def scripted_sweep(params: SceneParams, fps: float = CONTROL_FPS, speed: float = 2.0, height: float = 0.05) -> ToolPose:
    """A hand-made sweep that cuts every stalk of the patch (``grass_position``, ``grass_yaw``)
    within the first second: the level blade ``height`` (m) above the ground crosses the patch at
    ``speed`` (m/s, twice the scene's default minimum cutting speed) from 0.4 m before its centre
    to 0.4 m beyond, then holds 0.25 s (0.7 s in all at the defaults).
    Returns (T, 3) head positions and (T, 3, 3) rotations (world frame) at ``fps``."""
    patch = np.asarray(params["grass_position"], dtype=float)
    sweep = straight_sweep(patch, float(params["grass_yaw"]), speed, height, 1.0 / fps)
    return hold_last(sweep, int(np.ceil(0.25 * fps)))
