"""Joint-trajectory initialisation for the SQP: a greedy differential-IK rollout.

From ``q_0``, each step takes the move that minimises the *one-step* cost
``1/2 |r_t + J_t dq|^2 + damping / 2 |dq|^2`` (one damped Gauss-Newton step on the weighted pose
residual r_t of target t, Pinocchio LOCAL Jacobian, base fixed), clipped to the velocity limits and
then to the position limits. It is cheap (one forward kinematics and Jacobian per step) and starts
the SQP near the demonstrated motion instead of at a robot holding ``q_0``: a different local
optimum, sometimes much better (benchmark problem, video1 at time scale 4: J 1.81 against 2.27
when holding q_0; Crocoddyl from held q_0 reaches 2.00), sometimes worse (example at scale 4: 1.05
against 0.91); see :mod:`toolimit.trajopt.track`, which can run both.
"""

from __future__ import annotations

import numpy as np

from toolimit.trajopt.problem import TrackingProblem

#: Damping of the rollout steps (1 / rad^2 scale of J^T J): small, so each step goes most of the way.
ROLLOUT_DAMPING = 1e-2


def ik_rollout(problem: TrackingProblem, base: np.ndarray, damping: float = ROLLOUT_DAMPING) -> np.ndarray:
    """(T+1, N) joint trajectory from ``problem.q_start`` following the targets greedily, within
    position and velocity limits, for the base (3,) = (x, y, yaw)."""
    robot, dt = problem.robot, problem.dt
    step_limit = robot.velocity_limit * dt
    q = np.empty((problem.horizon + 1, problem.n_joints))
    q[0] = problem.q_start
    for t in range(1, problem.horizon + 1):
        residual, jacobian = problem.step_linearisation(base, q[t - 1], t)
        arm = jacobian[:, 3:]
        move = -arm.T @ np.linalg.solve(arm @ arm.T + damping * np.eye(6), residual)
        q[t] = np.clip(q[t - 1] + np.clip(move, -step_limit, step_limit), robot.lower, robot.upper)
    return q
