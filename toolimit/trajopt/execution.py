"""Replaying a robot's joint trajectory in a scene.

Robot replay puts the tool where forward kinematics puts it, so comparing
``replay(scene, params, rng, targets)`` (the tool alone) with ``execute_in_scene(robot, result,
scene, ...)`` shows what the robot's tracking errors cost in goal reward. The joint trajectory is
resampled (linearly in joint space) at the scene's ``control_dt`` when its own ``dt`` differs (time
scale).
"""

from __future__ import annotations

import numpy as np

from toolimit.errors import BaseInsideFootprint, InputError
from toolimit.robots import RobotModel
from toolimit.scenes.base import Scene, SceneParams
from toolimit.scenes.replay import replay
from toolimit.tools import ToolPose
from toolimit.trajopt.result import TrajectoryResult
from toolimit.trajopt.track import base_in_footprints


def resample_joints(q: np.ndarray, dt: float, control_dt: float) -> np.ndarray:
    """q (T+1, N) sampled every ``dt`` seconds, linearly interpolated every ``control_dt``."""
    if np.isclose(dt, control_dt, rtol=1e-9, atol=0.0):
        return q
    times = np.arange(len(q)) * dt
    new_times = np.arange(0.0, times[-1] + 1e-9, control_dt)
    return np.stack([np.interp(new_times, times, q[:, j]) for j in range(q.shape[1])], axis=1)


def execute_in_scene(
    robot: RobotModel,
    trajectory: TrajectoryResult,
    scene: Scene,
    params: SceneParams,
    rng: np.random.Generator,
    batch_size: int = 1,
) -> np.ndarray:
    """Replay the robot's joint trajectory in ``scene`` (tool pose by forward kinematics at
    ``trajectory.base``); returns the goal reward (B,).

    Raises InputError if the trajectory is not this robot's, BaseInsideFootprint if the base (x, y)
    stands inside a scene element's footprint (``scene.footprints(params)``).
    """
    if tuple(trajectory.joint_names) != tuple(robot.joint_names):
        raise InputError(f"trajectory joints {trajectory.joint_names} are not robot {robot.name}'s {robot.joint_names}")
    footprints = np.asarray(scene.footprints(params), dtype=float).reshape(-1, 5)
    hit = base_in_footprints(trajectory.base, footprints)
    if hit is not None:
        x, y = trajectory.base[:2]
        raise BaseInsideFootprint(
            f"robot base at (x={x:.3f}, y={y:.3f}) m stands inside scene element {hit} "
            f"(footprint centre {footprints[hit, :2].round(3).tolist()}, "
            f"half sizes {footprints[hit, 2:4].round(3).tolist()})"
        )
    q = resample_joints(trajectory.q, trajectory.dt, scene.control_dt)
    positions, rotations = robot.tool_poses(q, trajectory.base)
    return replay(scene, params, rng, ToolPose(positions, rotations), batch_size, tool_alone=False)
