"""Wrong on purpose: the predicted motion is J v instead of J v dt."""

from __future__ import annotations

import numpy as np
import osqp
import pinocchio as pin
import scipy.sparse as sp

from toolimit.robots import RobotModel

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = [
    "test_ex03_matches_reference_small_steps",
]


def diff_ik_step(
    robot: RobotModel,
    q: np.ndarray,
    target_position: np.ndarray,
    target_rotation: np.ndarray,
    dt: float,
    pose_weights: np.ndarray,
    velocity_weight: float,
    base: np.ndarray | None = None,
) -> np.ndarray:
    """v (N,) rad/s minimising |W (J v dt - e)|^2 + w_v |v|^2 within velocity and position limits."""
    q = np.asarray(q, dtype=float)
    base = np.zeros(3) if base is None else np.asarray(base, dtype=float)
    current = robot.tool_placement_world(q, base)
    target = pin.SE3(np.asarray(target_rotation, dtype=float), np.asarray(target_position, dtype=float))
    error = pin.log6(current.actInv(target)).vector  # (6,) in the tool frame
    jacobian = robot.tool_jacobian(q, base, reference="local")[:, 3:]  # (6, N), LOCAL
    weighted = np.asarray(pose_weights, dtype=float)[:, None] * jacobian  # W J (dt forgotten)
    target_motion = np.asarray(pose_weights, dtype=float) * error  # W e
    n = len(q)
    # |A v - b|^2 + w_v |v|^2 = v'(A'A + w_v I)v - 2 b'A v + const  ->  P = 2 (A'A + w_v I), q = -2 A'b
    hessian = sp.csc_matrix(2.0 * (weighted.T @ weighted + velocity_weight * np.eye(n)))
    gradient = -2.0 * weighted.T @ target_motion
    lower = np.maximum(-robot.velocity_limit, (robot.lower - q) / dt)
    upper = np.minimum(robot.velocity_limit, (robot.upper - q) / dt)
    solver = osqp.OSQP()
    solver.setup(
        hessian,
        gradient,
        sp.identity(n, format="csc"),
        lower,
        upper,
        eps_abs=1e-9,
        eps_rel=1e-9,
        polishing=True,
        verbose=False,
        max_iter=100000,
    )
    result = solver.solve(raise_error=False)
    if result.info.status_val != osqp.SolverStatus.OSQP_SOLVED:
        raise RuntimeError(f"OSQP did not solve the step: {result.info.status}")
    return np.clip(result.x, lower, upper)
