"""Grader of exercise 08: the banded QP of one SQP step, checked against the matrices written out
densely here from the exercise's formulas (the library's ``toolimit.trajopt.sqp`` builds the same
structure) on seeded random linearisations; the step against OSQP on the expected QP.

Each block (the pose term, the velocity band, the gradient, the constraints, the solve) is a part
of its own, so a submission gets the points of what it builds right.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import osqp
import pytest
import scipy.sparse as sp
from grading import case_seeds, check, fail, fmt, fmt_shape

MODULE = "ex08_tracking_qp"
#: Points of each test group (all its cases share them): 10 for the exercise.
WEIGHTS = {
    "test_ex08_hessian_pose_blocks": 2,
    "test_ex08_hessian_velocity_band": 2,
    "test_ex08_hessian_complete_and_banded": 1,
    "test_ex08_gradient": 2,
    "test_ex08_constraints": 2,
    "test_ex08_step_solves_the_qp": 1,
}
#: What each function returns, for the message on a value the checks cannot read.
RETURNS = {
    "tracking_qp": "a tuple (P, g, A, l, u): P and A scipy.sparse matrices, g, l, u 1-D arrays",
    "tracking_step": "a (T, N) float array of joint steps, rad",
}
#: Imported in the student's process before their module (it may start no thread afterwards).
STUDENT_IMPORTS = ["numpy", "scipy.sparse", "osqp"]
#: The library's trajectory optimisation (the same QP with the base): 0 points if called (grading.py).
FORBIDDEN = ["toolimit.trajopt", "toolimit.compare"]
TOLERANCE = 1e-9  # relative, matrix and vector entries
STEP_TOLERANCE = 1e-5  # rad between your step and the expected one


@dataclass(frozen=True)
class Case:
    description: str
    jacobians: np.ndarray  # (T, 6, N)
    residuals: np.ndarray  # (T, 6)
    q: np.ndarray  # (T + 1, N) rad
    dt: float
    velocity_weight: float
    damping: float
    lower: np.ndarray
    upper: np.ndarray
    velocity_limit: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        return self.residuals.shape[0], self.q.shape[1]

    def arguments(self) -> tuple:
        return (
            self.jacobians.copy(),
            self.residuals.copy(),
            self.q.copy(),
            self.dt,
            self.velocity_weight,
            self.damping,
            self.lower.copy(),
            self.upper.copy(),
            self.velocity_limit.copy(),
        )


def make_case(seed: int, terms: str = "all") -> Case:
    """``terms``: "pose" (w = mu = 0), "velocity" (J = r = 0, mu = 0), "all", "far" (large residuals:
    the velocity limits bind)."""
    rng = np.random.default_rng(seed)
    horizon, n = int(rng.integers(3, 16)), int(rng.integers(2, 8))
    dt = float(rng.uniform(0.02, 0.1))
    lower, upper = -rng.uniform(1.0, 3.0, n), rng.uniform(1.0, 3.0, n)
    velocity_limit = rng.uniform(0.5, 2.0, n)
    q = [rng.uniform(0.5 * lower, 0.5 * upper)]
    for _ in range(horizon):
        q.append(np.clip(q[-1] + dt * rng.uniform(-0.6, 0.6, n) * velocity_limit, lower, upper))
    jacobians = rng.normal(size=(horizon, 6, n))
    residuals = rng.normal(scale=3.0 if terms == "far" else 0.1, size=(horizon, 6))
    weight, damping = float(10 ** rng.uniform(-3, -1)), float(10 ** rng.uniform(-5, -2))
    if terms == "pose":
        weight, damping = 0.0, 0.0
    if terms == "velocity":
        jacobians, residuals, damping = np.zeros_like(jacobians), np.zeros_like(residuals), 0.0
    description = f"seed {seed} ({terms}): T = {horizon} steps, N = {n} joints, dt = {dt:.4f} s, w = {weight:.3g}, mu = {damping:.3g}"
    return Case(description, jacobians, residuals, np.array(q), dt, weight, damping, lower, upper, velocity_limit)


def expected_qp(case: Case) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(P, g, A, l, u), P and A dense, from the exercise's formulas."""
    horizon, n = case.shape
    size = horizon * n
    blocks = [slice(t * n, (t + 1) * n) for t in range(horizon)]
    difference = np.zeros((size, size))
    for t in range(horizon):
        difference[blocks[t], blocks[t]] = np.eye(n) / case.dt
        if t > 0:
            difference[blocks[t], blocks[t - 1]] = -np.eye(n) / case.dt
    hessian = 2.0 * case.velocity_weight * difference.T @ difference + case.damping * np.eye(size)
    gradient = np.zeros(size)
    velocities = np.diff(case.q, axis=0) / case.dt
    for t in range(horizon):
        hessian[blocks[t], blocks[t]] += 2.0 * case.jacobians[t].T @ case.jacobians[t]
        gradient[blocks[t]] += 2.0 * case.jacobians[t].T @ case.residuals[t]
    gradient += 2.0 * case.velocity_weight * difference.T @ velocities.ravel()
    constraints = np.vstack([np.eye(size), difference])
    low = np.concatenate([(case.lower - case.q[1:]).ravel(), (-case.velocity_limit - velocities).ravel()])
    high = np.concatenate([(case.upper - case.q[1:]).ravel(), (case.velocity_limit - velocities).ravel()])
    return hessian, gradient, constraints, low, high


def qp_of(submission, case: Case) -> tuple:
    got = submission(MODULE).tracking_qp(*case.arguments())
    check(
        isinstance(got, tuple) and len(got) == 5,
        lambda: (
            f"{case.description}: expected a tuple (P, g, A, l, u), got {fmt(got) if not isinstance(got, tuple) else f'a tuple of {len(got)}'}"
        ),
    )
    return got


def dense(matrix, name: str, shape: tuple[int, int], case: Case) -> np.ndarray:
    check(sp.issparse(matrix), lambda: f"{case.description}: {name} must be a scipy.sparse matrix, got {fmt(matrix)}")
    check(matrix.shape == shape, f"{case.description}: {name} must have shape {shape}, got {matrix.shape}")
    return matrix.toarray().astype(float)


def upper_triangle(matrix, case: Case) -> np.ndarray:
    """The student's P as its upper triangle (they may return it so, or the full symmetric P)."""
    horizon, n = case.shape
    full = dense(matrix, "P", (horizon * n, horizon * n), case)
    lower_part = np.tril(full, -1)
    if np.any(lower_part != 0) and not np.allclose(full, full.T, rtol=TOLERANCE, atol=1e-12):
        fail(f"{case.description}: P must be the upper triangle (what OSQP reads) or the full symmetric matrix")
    return np.triu(full)


def where_in(index: int, n: int) -> str:
    return f"step {index // n + 1}, joint {index % n}"


def compare_matrix(got: np.ndarray, expected: np.ndarray, name: str, case: Case, hint: str) -> None:
    scale = max(1.0, np.abs(expected).max())
    wrong = np.argwhere(np.abs(got - expected) > TOLERANCE * scale)
    if wrong.size:
        i, j = (int(k) for k in wrong[0])
        n = case.shape[1]
        fail(
            f"{case.description}: {name}[{i}, {j}] (row {where_in(i, n)}; column {where_in(j, n)}) should be "
            f"{fmt(expected[i, j], 8)}, got {fmt(got[i, j], 8)} ({len(wrong)} entries differ). {hint}"
        )


def compare_vector(got, expected: np.ndarray, name: str, case: Case, hint: str) -> None:
    try:
        got = np.asarray(got, dtype=float).ravel()
    except (TypeError, ValueError):
        fail(f"{case.description}: {name} must be a 1-D float array, got {fmt(got)}")
    check(
        got.shape == expected.shape,
        f"{case.description}: {name} must have shape {expected.shape}, got {fmt_shape(got)}",
    )
    scale = max(1.0, np.abs(expected).max())
    wrong = np.flatnonzero(np.abs(got - expected) > TOLERANCE * scale)
    if wrong.size:
        i = int(wrong[0])
        fail(
            f"{case.description}: {name}[{i}] should be {fmt(expected[i], 8)}, got {fmt(got[i], 8)} ({len(wrong)} differ). {hint}"
        )


@pytest.mark.parametrize("seed", case_seeds(4))
def test_ex08_hessian_pose_blocks(submission, seed):
    case = make_case(seed, "pose")
    hessian = qp_of(submission, case)[0]
    compare_matrix(
        upper_triangle(hessian, case),
        np.triu(expected_qp(case)[0]),
        "P",
        case,
        "With w = mu = 0, P is block diagonal: 2 J_t'J_t for step t (the factor 2 of f = 1/2 x'Px).",
    )


@pytest.mark.parametrize("seed", case_seeds(4, 10))
def test_ex08_hessian_velocity_band(submission, seed):
    case = make_case(seed, "velocity")
    hessian = qp_of(submission, case)[0]
    compare_matrix(
        upper_triangle(hessian, case),
        np.triu(expected_qp(case)[0]),
        "P",
        case,
        "With J = 0 and mu = 0, P = 2 w D'D: 4 w / dt^2 on the diagonal of steps 1..T-1, 2 w / dt^2 on the "
        "last step's (it is in one difference only), -2 w / dt^2 between neighbouring steps.",
    )


@pytest.mark.parametrize("seed", case_seeds(4, 20))
def test_ex08_hessian_complete_and_banded(submission, seed):
    case = make_case(seed, "all")
    hessian = qp_of(submission, case)[0]
    got = upper_triangle(hessian, case)
    compare_matrix(got, np.triu(expected_qp(case)[0]), "P", case, "P = pose blocks + 2 w D'D + mu I.")
    n = case.shape[1]
    rows, cols = np.nonzero(hessian.toarray())
    width = int(np.abs(rows - cols).max(initial=0))
    check(
        width <= 2 * n - 1,
        f"{case.description}: P holds a non-zero {width} columns off the diagonal (at most 2 N - 1 = {2 * n - 1}): keep it banded",
    )


@pytest.mark.parametrize("seed", case_seeds(4, 30))
def test_ex08_gradient(submission, seed):
    case = make_case(seed, "all")
    gradient = qp_of(submission, case)[1]
    compare_vector(
        gradient,
        expected_qp(case)[1],
        "g",
        case,
        "g = 2 J_t' r_t for step t, plus 2 w D' v (v the current velocities, (T N,)).",
    )


@pytest.mark.parametrize("seed", case_seeds(4, 40))
def test_ex08_constraints(submission, seed):
    case = make_case(seed, "all")
    _, _, constraints, low, high = qp_of(submission, case)
    _, _, a_expected, l_expected, u_expected = expected_qp(case)
    horizon, n = case.shape
    compare_matrix(
        dense(constraints, "A", a_expected.shape, case),
        a_expected,
        "A",
        case,
        "A = [I; D]: the T N joint-limit rows, then the T N velocity rows (dq_t - dq_{t-1}) / dt.",
    )
    compare_vector(low, l_expected, "l", case, "l = (lower - q_t for t = 1..T, then -vlim - v_t).")
    compare_vector(high, u_expected, "u", case, "u = (upper - q_t for t = 1..T, then vlim - v_t).")


def solve(case: Case) -> np.ndarray:
    hessian, gradient, constraints, low, high = expected_qp(case)
    solver = osqp.OSQP()
    solver.setup(
        sp.csc_matrix(np.triu(hessian)),
        gradient,
        sp.csc_matrix(constraints),
        low,
        high,
        verbose=False,
        eps_abs=1e-10,
        eps_rel=1e-10,
        max_iter=200000,
        polishing=True,
    )
    result = solver.solve(raise_error=False)
    assert result.info.status_val == osqp.SolverStatus.OSQP_SOLVED, f"grader's QP failed: {result.info.status}"
    return result.x.reshape(case.shape)


@pytest.mark.parametrize("terms", ["all", "far"])
@pytest.mark.parametrize("seed", case_seeds(2, 50))
def test_ex08_step_solves_the_qp(submission, seed, terms):
    case = make_case(seed, terms)
    expected = solve(case)
    got = submission(MODULE).tracking_step(*case.arguments())
    try:
        got = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        fail(f"{case.description}: expected a {case.shape} float array of steps, got {fmt(got)}")
    check(got.shape == case.shape, f"{case.description}: expected shape {case.shape}, got {fmt_shape(got)}")
    gap = np.abs(got - expected)
    if gap.max() > STEP_TOLERANCE:
        t, j = (int(k) for k in np.unravel_index(np.argmax(gap), gap.shape))
        velocities = (
            np.diff(np.vstack([np.zeros(case.shape[1]), expected]), axis=0) / case.dt
            + np.diff(case.q, axis=0) / case.dt
        )
        binding = int(np.sum(np.abs(np.abs(velocities) - case.velocity_limit) < 1e-6))
        fail(
            f"{case.description}: step {t + 1}, joint {j}: expected {expected[t, j]:.6f} rad, got {got[t, j]:.6f} "
            f"(tolerance {STEP_TOLERANCE:g}); {binding} velocity limits bind in the expected answer"
        )
