"""Exercise 08 (an evening): the banded QP of one SQP step of trajectory optimisation (stage iii).

Trajectory optimisation (``toolimit.trajopt``, notebook 03) tracks the demonstration's tool poses
over a whole horizon: each SQP iteration linearises the pose errors around the current joint
trajectory and solves ONE quadratic program for the steps of all joint positions at once. With the
joint *positions* as variables, the velocity term only couples neighbouring steps, so the QP's
matrices are banded (block tridiagonal) and sparse; with the velocities as variables they would be
dense. You build that QP and solve it with OSQP. Each function and each block is graded on its own
(partial credit per part).

Notation (all arrays float): T steps, N joints, dt seconds per step.
- ``q`` (T + 1, N): the current joint positions q_0 .. q_T (rad); q_0 is fixed (the start).
- The variables are the steps x = (dq_1, ..., dq_T), a vector of T N numbers, step t's N values at
  x[(t - 1) N : t N]; dq_0 = 0.
- ``jacobians`` (T, 6, N) and ``residuals`` (T, 6): the weighted pose residual of step t is
  linearised as r_t + J_t dq_t (Gauss-Newton).
- The current velocities are v_t = (q_t - q_{t-1}) / dt, t = 1..T; after the step they are
  v_t + (dq_t - dq_{t-1}) / dt.

The QP minimises
    f(x) = sum_t |r_t + J_t dq_t|^2 + w sum_t |v_t + (dq_t - dq_{t-1}) / dt|^2 + (mu / 2) |x|^2
(w = ``velocity_weight``, mu = ``damping``), written as f(x) = 1/2 x'Px + g'x + constant, subject to
    lower - q_t <= dq_t <= upper - q_t               (the joint limits, T N rows), then
    -vlim - v_t <= (dq_t - dq_{t-1}) / dt <= vlim - v_t   (the velocity limits, T N rows).

Check your work with ``python grade.py check --exercise ex08`` in the course folder (in the
project's repository: ``python course/grade.py check --exercise ex08``); see README.md. Write it
yourself: a submission that calls the library's trajectory optimisation scores 0 for the exercise.

Written questions (answer in a few sentences each, in a file ``ex08_answers.md`` handed in with
this one):
1. Count the non-zeros of P and A for T = 92, N = 7 with your construction, and estimate them for
   the condensed form (the velocities as variables, the positions as their cumulative sums). Which
   is cheaper for OSQP, and why?
2. The library adapts ``damping`` from the ratio of the actual to the predicted decrease of the
   true cost (Levenberg-Marquardt). What goes wrong with mu = 0 far from the solution, and with a
   very large mu?
3. Between two SQP iterations, which of P, g, A, l, u change? What does this let the solver reuse
   (the library sets OSQP up once per run)?
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def tracking_qp(
    jacobians: np.ndarray,
    residuals: np.ndarray,
    q: np.ndarray,
    dt: float,
    velocity_weight: float,
    damping: float,
    lower: np.ndarray,
    upper: np.ndarray,
    velocity_limit: np.ndarray,
) -> tuple[sp.spmatrix, np.ndarray, sp.spmatrix, np.ndarray, np.ndarray]:
    """Return the QP (P, g, A, l, u) of the module docstring.

    P: a scipy.sparse (T N, T N) matrix, either its upper triangle (what OSQP reads) or the full
    symmetric matrix; it must stay banded: no non-zero more than 2 N - 1 columns off the diagonal.
    g: (T N,). A: a scipy.sparse (2 T N, T N) matrix, the T N joint-limit rows first, then the
    T N velocity rows, both in the variables' order. l, u: (2 T N,). ``lower``, ``upper`` and
    ``velocity_limit`` are (N,) (rad, rad/s).
    """
    raise NotImplementedError("exercise 08: build the banded QP")


def tracking_step(
    jacobians: np.ndarray,
    residuals: np.ndarray,
    q: np.ndarray,
    dt: float,
    velocity_weight: float,
    damping: float,
    lower: np.ndarray,
    upper: np.ndarray,
    velocity_limit: np.ndarray,
) -> np.ndarray:
    """Return the optimal steps dq as a (T, N) array (rad): the QP of :func:`tracking_qp` solved with
    OSQP (``osqp.OSQP().setup(P, g, A, l, u, ...)``; ask for a tight tolerance, e.g. 1e-9)."""
    raise NotImplementedError("exercise 08: solve the QP")
