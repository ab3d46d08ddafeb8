"""A hand-made scoop-carry-tip motion of the spade for the 3D spade scene (tests, benchmarks, notebooks).

A motion generator, kept apart from the scene it is made for: it reads the scene's parameters and
the spade's geometry, and returns tool poses any scene replay can follow.
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.base import CONTROL_FPS, SceneParams
from toolimit.scenes.spade_keyframes import spade_keyframe_motion
from toolimit.scenes.spatial.tool_geometry import SPADE_BLADE_LENGTH
from toolimit.tools import ToolPose, rotation_z


def scripted_scoop(params: SceneParams, fps: float = CONTROL_FPS) -> ToolPose:
    """A hand-made scoop-carry-tip spade motion for a scene's parameters (tests, benchmarks, notebooks).

    The spade enters the deposit through its open side with the blade nearly flat on the ground
    (handle 12 degrees up), slides under the pile to 8 cm from the back wall, lifts 0.3 m while
    tilting the tip up 10 degrees (sand rests against the back rim), carries the blade over the goal
    box, then raises the handle to 80 degrees (beyond the 68-degree friction angle of the sand on
    the blade) so the sand slides off the open tip, and holds.
    Returns (T, 3) head positions and (T, 3, 3) rotations (world frame) at ``fps``.
    """
    sand = np.asarray(params["sand_position"], dtype=float) * np.array([1.0, 1.0, 0.0])
    goal = np.asarray(params["goal_position"], dtype=float) * np.array([1.0, 1.0, 0.0])
    yaw = float(params["sand_yaw"])
    heading = rotation_z(yaw) @ np.array([0.0, 1.0, 0.0])  # horizontal direction from tip to handle
    up = np.array([0.0, 0.0, 1.0])
    blade_middle = SPADE_BLADE_LENGTH / 2
    deg = np.pi / 180
    keyframes = [  # time (s), head position (m), handle elevation (rad)
        (0.0, sand + 0.45 * heading + 0.008 * up, 12 * deg),
        (1.2, sand - 0.12 * heading + 0.008 * up, 12 * deg),
        (1.7, sand - 0.05 * heading + 0.30 * up, -10 * deg),
        (2.9, goal - blade_middle * heading + 0.30 * up, -10 * deg),
        (3.5, goal - blade_middle * heading + 0.20 * up, 80 * deg),
        (4.5, goal - blade_middle * heading + 0.20 * up, 80 * deg),
    ]
    return spade_keyframe_motion(keyframes, heading, fps)
