"""rerun recording of an optimised robot trajectory: tracking errors over time, joints and limits.

Entities (timeline ``time``, seconds): ``errors/position_cm`` and ``errors/rotation_deg`` per step;
``joints/<name>/q`` with ``joints/<name>/lower`` and ``.../upper`` (rad) as constant lines;
``velocity/<name>/ratio`` = |v| / limit (1 = at the limit); ``tool/target`` and ``tool/robot``
3D points (world frame, metres).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr

from toolimit.robots import RobotModel
from toolimit.trajopt.result import TrajectoryResult
from toolimit.viz.rerun_file import recording_file

TARGET_COLOUR = (230, 120, 30)
ROBOT_COLOUR = (60, 140, 230)


def save_trajectory_recording(
    result: TrajectoryResult, robot: RobotModel, path: str | Path, target_positions: np.ndarray | None = None
) -> Path | None:
    """Write the recording of ``result`` to ``path`` (.rrd); None when rerun is disabled.

    ``target_positions`` (T, 3) adds the target tool path beside the robot's.
    """
    with recording_file(path, "toolimit_trajopt") as recording:
        if recording is None:
            return None
        _log_trajectory(recording, result, robot, target_positions)
    return Path(path)


def _log_trajectory(
    recording: rr.RecordingStream, result: TrajectoryResult, robot: RobotModel, target_positions: np.ndarray | None
) -> None:
    tool_positions, _ = robot.tool_poses(result.q, result.base)
    recording.log("tool/robot", rr.LineStrips3D([tool_positions], colors=[ROBOT_COLOUR]), static=True)
    if target_positions is not None:
        recording.log(
            "tool/target", rr.LineStrips3D([np.asarray(target_positions)], colors=[TARGET_COLOUR]), static=True
        )
    for t in range(len(result.q)):
        recording.set_time("time", duration=t * result.dt)
        if t >= 1:
            recording.log("errors/position_cm", rr.Scalars(100.0 * float(result.position_error[t - 1])))
            recording.log("errors/rotation_deg", rr.Scalars(float(np.degrees(result.rotation_error[t - 1]))))
        for j, name in enumerate(result.joint_names):
            recording.log(f"joints/{name}/q", rr.Scalars(float(result.q[t, j])))
            recording.log(f"joints/{name}/lower", rr.Scalars(float(robot.lower[j])))
            recording.log(f"joints/{name}/upper", rr.Scalars(float(robot.upper[j])))
            if t >= 1:
                recording.log(f"velocity/{name}/ratio", rr.Scalars(float(result.velocity_ratio[t - 1, j])))
        recording.log("tool/robot_now", rr.Points3D([tool_positions[t]], colors=[ROBOT_COLOUR], radii=0.02))
