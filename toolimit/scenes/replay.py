"""Replaying a tool motion in a scene: the one loop behind alignment, robot execution, views and checks.

``replay`` resets the scene once (its only draws from ``rng``), steps the tool through the poses and
reads the goal reward; a per-step hook sees the scene after every step (a view takes a snapshot, a
recording logs it).

The tool alone moves as the authors' tool-alone replay moves it (pyphysx_envs ``utils.py
follow_tool_tip_traj`` and ``ToolEnv.step``): at every control step it is driven towards the next
target pose with the velocity that would reach it in one step, clipped per world axis to 1 m/s and
2 rad/s, so a motion faster than that lags behind its targets and catches up where it slows down
(:func:`speed_limited`). A robot's replay (forward kinematics of its joint trajectory) is replayed
as given: the robot's own limits bound it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from toolimit.rotations import rotation_matrices, rotation_vectors
from toolimit.scenes.base import Scene, SceneParams
from toolimit.tools import ToolPose, tool_spec

#: Called after step t (0-based) with the scene, e.g. to take a snapshot.
StepHook = Callable[[int, Scene], None]


class SpeedLimit(NamedTuple):
    """Per-axis bounds of the tool's velocity in the world frame: linear (m/s) of its steered point,
    angular (rad/s)."""

    linear: float
    angular: float


#: The authors' tool-alone replay clips the commanded velocity to these per axis (``ToolEnv.step``).
TOOL_SPEED_LIMIT = SpeedLimit(linear=1.0, angular=2.0)


def speed_limited(poses: ToolPose, dt: float, steered_offset: float, limit: SpeedLimit = TOOL_SPEED_LIMIT) -> ToolPose:
    """The poses a speed-limited tool reaches when driven towards ``poses`` (T, 3) / (T, 3, 3) (world
    frame, m), one target per control step of ``dt`` s.

    The first pose is where the tool is placed. At each later step the tool turns by the rotation
    vector (world frame) from its current to the target rotation, each component clipped to
    ``limit.angular * dt``, about its steered point (``steered_offset`` m from the head along the
    tool's z axis), which moves towards its target by the difference clipped per axis to
    ``limit.linear * dt``. A motion within the limits is returned unchanged.
    """
    positions = np.array(poses.position, dtype=float)
    rotations = np.array(poses.rotation, dtype=float)
    max_move, max_turn = limit.linear * dt, limit.angular * dt
    for t in range(1, len(positions)):
        rotation = rotations[t - 1]
        steered = positions[t - 1] + steered_offset * rotation[:, 2]
        target_steered = poses.position[t] + steered_offset * poses.rotation[t][:, 2]
        turn = np.clip(rotation_vectors(poses.rotation[t] @ rotation.T), -max_turn, max_turn)
        rotation = rotation_matrices(turn) @ rotation
        steered = steered + np.clip(target_steered - steered, -max_move, max_move)
        rotations[t] = rotation
        positions[t] = steered - steered_offset * rotation[:, 2]
    return ToolPose(positions, rotations)


def replay(
    scene: Scene,
    params: SceneParams,
    rng: np.random.Generator,
    poses: ToolPose,
    batch_size: int = 1,
    on_step: StepHook | None = None,
    tool_alone: bool = True,
) -> np.ndarray:
    """Reset B instances of ``scene`` with ``params`` (drawing from ``rng``), step the tool through
    ``poses`` ((T, 3) positions m, (T, 3, 3) world-from-tool rotations, world frame), calling
    ``on_step(t, scene)`` after step t; returns the final goal reward (B,).

    ``tool_alone``: the tool alone follows the poses within :data:`TOOL_SPEED_LIMIT`
    (:func:`speed_limited`, about the scene's tool's ``steered_point``); False for poses a robot's
    forward kinematics gives, replayed as they are.

    Raises InvalidSceneParameters (from ``reset``) when ``params`` cannot make the scene.
    """
    if tool_alone:
        poses = speed_limited(poses, scene.control_dt, tool_spec(scene.tool).steered_offset)
    scene.reset(params, rng, batch_size)
    for t, (position, rotation) in enumerate(zip(poses.position, poses.rotation)):
        scene.step(ToolPose(position, rotation))
        if on_step is not None:
            on_step(t, scene)
    return np.asarray(scene.goal_reward(), dtype=float).reshape(batch_size)
