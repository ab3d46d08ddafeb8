"""Static reachability: can the arm put its tool head on each target position, base fixed?

Per target, a position-only inverse kinematics (damped least squares on the tool head position,
joints clipped to their limits after every step) from two starts: the trajectory's own
configuration and the rest pose. A target is reachable when one of them ends within
``tolerance`` metres. This separates tracking errors the optimiser could remove (reachable steps)
from those the robot's workspace imposes.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from toolimit.robots import RobotModel

#: Position error (m) under which a target counts as reached.
REACH_TOLERANCE = 0.01


def reachable_steps(
    robot: RobotModel,
    base: np.ndarray,
    positions: np.ndarray,
    q_init: np.ndarray | None = None,
    tolerance: float = REACH_TOLERANCE,
    iterations: int = 60,
    damping: float = 1e-3,
) -> np.ndarray:
    """(T,) bool: target positions (T, 3) (world, m) reachable by the tool head with the base at
    ``base`` (3,) and the joints within limits. ``q_init`` (T, N) are per-target IK starts."""
    positions = np.asarray(positions, dtype=float)
    starts = [np.tile(robot.q_neutral, (len(positions), 1))]
    if q_init is not None:
        starts.insert(0, np.asarray(q_init, dtype=float))
    model, data, frame = robot.full_model, robot.full_model.createData(), robot.full_tool_frame_id
    reached = np.zeros(len(positions), dtype=bool)
    q_full = np.empty(3 + robot.n_joints)
    q_full[:3] = base
    for t, target in enumerate(positions):
        for start in starts:
            q = np.clip(start[t], robot.lower, robot.upper)
            for _ in range(iterations):
                q_full[3:] = q
                pin.computeJointJacobians(model, data, q_full)
                placement = pin.updateFramePlacement(model, data, frame)
                error = target - placement.translation
                if np.linalg.norm(error) < tolerance:
                    break
                jacobian = pin.getFrameJacobian(model, data, frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3, 3:]
                step = jacobian.T @ np.linalg.solve(jacobian @ jacobian.T + damping * np.eye(3), error)
                q = np.clip(q + step, robot.lower, robot.upper)
            else:
                q_full[3:] = q
                pin.forwardKinematics(model, data, q_full)
                error = target - pin.updateFramePlacement(model, data, frame).translation
            if np.linalg.norm(error) < tolerance:
                reached[t] = True
                break
    return reached
