"""Solve a :class:`BaseTrackingProblem` with Crocoddyl's SolverBoxFDDP (the reference solver).

Crocoddyl is optional: it is imported only when a function here is called, with an error saying
how to install it.
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from toolimit.compare.tracking_problem import BaseTrackingProblem

DEFAULT_MAX_ITERATIONS = 200


def _models() -> ModuleType:
    """The crocoddyl action models; raises ImportError with the install command if crocoddyl is absent."""
    return importlib.import_module("toolimit.compare.crocoddyl_models")


@dataclass(frozen=True)
class CrocoddylSolution:
    """SolverBoxFDDP's answer from one initial base guess.

    Attributes:
        q_trajectory: (T+1, nq) configurations q_0..q_T (base first; m, rad); Crocoddyl's xs, so
            q_0 holds the base guess and the base found is ``q_trajectory[1, :n_base]``.
        u_trajectory: (T, nq) controls u_0..u_{T-1} = [db_k, v_{k+1}] (m, rad; rad/s for v).
        cost: the solver's final cost (the problem's J).
        iterations: solver iterations run.
        converged: whether the solver met its stopping criterion.
        solve_time_s: wall time of ``solver.solve`` alone, seconds.
    """

    q_trajectory: np.ndarray
    u_trajectory: np.ndarray
    cost: float
    iterations: int
    converged: bool
    solve_time_s: float


def solve_with_crocoddyl(
    problem: BaseTrackingProblem,
    base_guess: np.ndarray,
    max_iterations: int = DEFAULT_MAX_ITERATIONS,
    th_stop: float | None = None,
) -> CrocoddylSolution:
    """Solve from ``q_0 = [base_guess, arm of problem.q0]``, trajectory initialised at rest.

    ``xs = [x0] * (T+1)``, ``us = 0`` is a rollout, so it is passed as feasible:
    ``solver.solve(xs, us, max_iterations, True)``. ``th_stop`` overrides the solver default
    (5e-5 in crocoddyl 3.2.1).
    """
    models = _models()
    crocoddyl = models.crocoddyl
    base_guess = np.asarray(base_guess, dtype=float)
    if base_guess.shape != (problem.n_base,):
        raise ValueError(f"base_guess must have shape ({problem.n_base},), got {base_guess.shape}")
    x0 = np.concatenate([base_guess, problem.q0[problem.n_base :]])
    shooting = models.shooting_problem(problem, x0)
    solver = crocoddyl.SolverBoxFDDP(shooting)
    if th_stop is not None:
        solver.th_stop = th_stop
    xs = [x0.copy() for _ in range(problem.horizon + 1)]
    us = [np.zeros(problem.model.nq) for _ in range(problem.horizon)]
    start = time.perf_counter()
    converged = solver.solve(xs, us, max_iterations, True)
    elapsed = time.perf_counter() - start
    return CrocoddylSolution(
        q_trajectory=np.array(solver.xs),
        u_trajectory=np.array(solver.us),
        cost=float(solver.cost),
        iterations=int(solver.iter),
        converged=bool(converged),
        solve_time_s=elapsed,
    )
