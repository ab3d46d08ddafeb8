"""A hand-made scoop-carry-tip motion of the spade for the planar spade scene (tests, LfD baseline).

A motion generator, kept apart from the scene it is made for: it reads the scene's parameters and
returns tool poses any scene replay can follow (the x-z plane, y = 0).
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.base import CONTROL_FPS, SceneParams
from toolimit.scenes.spade_keyframes import spade_keyframe_motion
from toolimit.tools import ToolPose


def scripted_scoop(params: SceneParams, fps: float = CONTROL_FPS) -> ToolPose:
    """A hand-made scoop-carry-tip spade motion for the planar spade scene's parameters.

    The spade comes in from the side of the deposit away from the goal box, tip first and tilted 5
    degrees handle up, lowers its blade to 3.5 cm above the ground (under the pile's top layers,
    above the tray's floor circles), slides 12 cm past the deposit's centre, lifts 0.25 m while
    tilting the tip up 12 degrees (the sand slides back against the heel lip), carries the blade
    over the goal box at 0.3 m, raises the handle to 60 degrees so the sand slides off the tip
    into the box, and holds for 0.3 s: 3.3 s in all. Only the x of ``sand_position`` and
    ``goal_position`` is used; the goal box may be on either side of the deposit.
    Returns (T, 3) head positions and (T, 3, 3) rotations (world frame) at ``fps``.
    """
    sand = float(np.asarray(params["sand_position"], dtype=float)[0])
    goal = float(np.asarray(params["goal_position"], dtype=float)[0])
    forward = 1.0 if goal >= sand else -1.0  # from the deposit towards the goal box along x
    deg = np.pi / 180

    def at(x: float, z: float) -> np.ndarray:
        return np.array([x, 0.0, z])

    keyframes = [  # time (s), head position (m), handle elevation (rad)
        (0.0, at(sand - 0.50 * forward, 0.10), 5 * deg),
        (0.4, at(sand - 0.32 * forward, 0.035), 0.0),
        (1.2, at(sand + 0.12 * forward, 0.035), 0.0),
        (1.6, at(sand + 0.15 * forward, 0.25), -12 * deg),
        (2.4, at(goal - 0.15 * forward, 0.30), -12 * deg),
        (3.0, at(goal - 0.08 * forward, 0.25), 50 * deg),
        (3.3, at(goal - 0.08 * forward, 0.25), 60 * deg),
    ]
    return spade_keyframe_motion(keyframes, np.array([-forward, 0.0, 0.0]), fps)
