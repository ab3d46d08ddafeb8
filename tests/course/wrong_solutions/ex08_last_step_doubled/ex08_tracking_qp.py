"""Wrong: every step's diagonal gets two velocity differences, the last one too (it is in one only)."""

from __future__ import annotations

import numpy as np
import osqp
import scipy.sparse as sp

CAUGHT_BY = ["test_ex08_hessian_velocity_band"]


def tracking_qp(jacobians, residuals, q, dt, velocity_weight, damping, lower, upper, velocity_limit):
    """(P upper triangle, g, A, l, u) of the banded tracking QP."""
    jacobians, residuals, q = (np.asarray(a, dtype=float) for a in (jacobians, residuals, q))
    horizon, _, n = jacobians.shape
    size = horizon * n
    velocities = np.diff(q, axis=0) / dt  # (T, N)
    # the pose term: one N x N block per step
    pose = sp.block_diag([2.0 * jac.T @ jac for jac in jacobians], format="csc")
    # the velocity differences D x = ((dq_t - dq_{t-1}) / dt), dq_0 = 0
    difference = sp.diags([np.ones(size), -np.ones(size - n)], [0, -n], format="csc") / dt
    hessian = pose + 2.0 * velocity_weight * (difference.T @ difference) + damping * sp.identity(size)
    hessian = hessian + sp.diags(np.r_[np.zeros(size - n), np.full(n, 2.0 * velocity_weight / dt**2)])
    gradient = 2.0 * np.einsum("tkn,tk->tn", jacobians, residuals).ravel()
    gradient += 2.0 * velocity_weight * (difference.T @ velocities.ravel())
    constraints = sp.vstack([sp.identity(size, format="csc"), difference], format="csc")
    low = np.concatenate([(lower - q[1:]).ravel(), (-velocity_limit - velocities).ravel()])
    high = np.concatenate([(upper - q[1:]).ravel(), (velocity_limit - velocities).ravel()])
    return sp.triu(hessian, format="csc"), gradient, constraints, low, high


def tracking_step(jacobians, residuals, q, dt, velocity_weight, damping, lower, upper, velocity_limit):
    """(T, N) steps solving the QP with OSQP."""
    hessian, gradient, constraints, low, high = tracking_qp(
        jacobians, residuals, q, dt, velocity_weight, damping, lower, upper, velocity_limit
    )
    solver = osqp.OSQP()
    solver.setup(
        hessian,
        gradient,
        constraints,
        low,
        high,
        verbose=False,
        eps_abs=1e-10,
        eps_rel=1e-10,
        max_iter=200000,
        polishing=True,
    )
    steps = solver.solve().x
    return np.clip(steps, low[: len(steps)], high[: len(steps)]).reshape(len(residuals), -1)
