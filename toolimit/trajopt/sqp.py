"""Sequential quadratic programming (OSQP) for one base initialisation.

Each iteration linearises the tool pose around the current trajectory (Gauss-Newton, Pinocchio
frame Jacobians and ``Jlog6``) and solves ONE sparse QP over the whole horizon for the step
``x = (db, dq_1..dq_T)``: base step (active base coordinates) and joint-position steps. Keeping the
joint positions as variables (the velocities are their differences) makes the QP banded: the
Hessian has one N x N block per step, the velocity term couples neighbouring steps (diagonal
blocks), and the base is a column block shared by all steps. Constraints (the matrix ``A`` is
constant, only the bounds change):

* joint limits ``lower <= q_t + dq_t <= upper``;
* velocity limits ``|(q_t + dq_t - q_{t-1} - dq_{t-1}) / dt| <= vlim`` (``dq_0 = 0``);
* for a bound with an acceleration limit (:class:`~toolimit.robots.motion_bound.MotionBound`:
  robots with published limits), the velocity change of each step
  ``|(q_{t+1} - 2 q_t + q_{t-1}) / dt| <= alim dt`` with the arm at rest before the start
  (``q_{-1} = q_0``), so that the robot can execute the trajectory at its timing (on the control
  grid, where learning replays it, the resampled steps keep the bound when dt is the control step).
  These rows are in rad/s, as the velocity rows are, so that OSQP's absolute tolerance means the
  same on both; in rad/s^2 it would be 1/dt times tighter on them, for no better trajectory and
  about twice the ADMM iterations (docs/results/performance.md).

The bounds are the problem's ``bound``: positions, velocities and accelerations the learning
environment also holds the robot to.

The step is damped Levenberg-Marquardt style (``mu |x|^2 / 2``, adapted from the ratio of actual to
predicted decrease) and accepted by a backtracking line search on the true nonlinear J. Because
constraints are linear and the current iterate feasible, every step length in [0, 1] stays
feasible up to OSQP's tolerance; the accepted trajectory is then *projected* by a forward rollout
(each step commanded through the bound: :meth:`MotionBound.step
<toolimit.robots.motion_bound.MotionBound.step>`), so returned trajectories satisfy the limits
exactly (to floating-point rounding).

The condensed alternative (joint velocities as the only variables, positions as cumulative sums)
makes P and A dense: on the benchmark problem (T = 92, N = 7) its first QP has 210k + 31k
non-zeros against 5k + 2k here and took 0.70 s against 0.012 s to set up and solve (same optimum).

OSQP is set up once per run and updated each iteration (``Px``, ``q``, ``l``, ``u``: the sparsity
pattern is fixed), warm-started from a zero step and the previous multipliers: on the benchmark
problem this takes 2.3 times fewer ADMM iterations than a fresh setup per iteration.

Stops when an iteration decreases J, or the QP model predicts a decrease, of less than
``relative_tolerance * J`` (1e-6 by default). On the benchmark problem the 8-start result ends
1.1e-4 (spade_video1_aligned, where the reference solution itself violates the joint limits that
are hard here) and -5e-7 (spade_example_aligned) relative from Crocoddyl's J.
"""

from __future__ import annotations

import contextlib
import io
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
import osqp
import scipy.sparse as sp

from toolimit.errors import InputError, SolverFailure
from toolimit.robots.motion_bound import MotionBound, motion_from_rest
from toolimit.trajopt.costs import Iterate, QuadraticModel
from toolimit.trajopt.problem import TrackingProblem


@dataclass(frozen=True)
class SqpOptions:
    """Settings of the SQP loop and of OSQP.

    Attributes:
        max_iterations: SQP iterations at most.
        relative_tolerance: stop when J decreases by less than this fraction of J in an iteration.
        initial_damping: mu of the first iteration (units of the Hessian: 1 / rad^2).
        max_damping: the run stops (converged) when no step length decreases J and mu, multiplied
            by 10 after each such failure, exceeds this.
        osqp_eps: OSQP's eps_abs and eps_rel. With polishing (which solves the KKT system of the
            detected active set exactly), 5e-3 reaches the same J as 1e-6 to 1e-6 relative on the
            benchmark problem (PROBLEM.md) with 3 to 4 times fewer ADMM iterations; 3e-2 was
            too loose there (a start fell into a worse basin).
        osqp_max_iter: OSQP iterations per QP at most.
        osqp_rho: OSQP's initial ADMM step rho (1.0 needs ~25 % fewer iterations than 0.1 here).
        osqp_adaptive_rho_tolerance: OSQP re-tunes rho when its estimate changes by this factor.
        polishing: OSQP polishing (exact active sets).
        line_search_steps: step lengths tried: 1, 1/2, ..., 1/2^(steps-1).
    """

    max_iterations: int = 100
    relative_tolerance: float = 1e-6
    initial_damping: float = 1e-3
    max_damping: float = 1e6
    osqp_eps: float = 5e-3
    osqp_max_iter: int = 10000
    osqp_rho: float = 1.0
    osqp_adaptive_rho_tolerance: float = 2.0
    polishing: bool = True
    line_search_steps: int = 10

    def __post_init__(self) -> None:
        if self.max_iterations < 0:
            raise InputError(f"max_iterations must be >= 0, got {self.max_iterations}")
        for name in ("relative_tolerance", "osqp_eps"):
            if not getattr(self, name) > 0:
                raise InputError(f"{name} must be positive, got {getattr(self, name)}")
        if self.initial_damping < 0:
            raise InputError(f"initial_damping must be >= 0, got {self.initial_damping}")
        if self.line_search_steps < 1:
            raise InputError(f"line_search_steps must be >= 1, got {self.line_search_steps}")


@dataclass(frozen=True)
class SqpOutcome:
    """The result of one SQP run.

    Attributes:
        base: (3,) base x, y (m), yaw (rad).
        q: (T+1, N) joint trajectory, q[0] = q_start, radians; within the limits.
        cost: J at (base, q).
        iterations: SQP iterations done.
        qp_iterations: total OSQP iterations.
        converged: the relative-decrease test stopped the loop (not max_iterations).
        stopped_early: ``stop_early`` ended the run.
        wall_time_s: seconds.
        cost_history: J after each iteration (the first entry is the initial J).
    """

    base: np.ndarray
    q: np.ndarray
    cost: float
    iterations: int
    qp_iterations: int
    converged: bool
    stopped_early: bool
    wall_time_s: float
    cost_history: tuple[float, ...]


def project_to_limits(q: np.ndarray, dt: float, bound: MotionBound) -> np.ndarray:
    """Forward rollout of q (T+1, N) from q[0] at rest that commands each step's move through
    ``bound`` (velocity, acceleration, position range). q[0] must be within the range; the result
    satisfies the bound. A trajectory that satisfies it already is returned as it is."""
    q = np.asarray(q, dtype=float)
    if bound.holds(q, dt):
        return q.copy()
    return bound.follow(q, dt)


class _TrackingQp:
    """The QP of one SQP iteration with a fixed sparsity pattern (see the module docstring).

    Variables: ``x = (db (nb), dq_1 (N), ..., dq_T (N))``.
    """

    def __init__(self, problem: TrackingProblem, base_mask: np.ndarray, options: SqpOptions) -> None:
        self.problem = problem
        self.base_columns = np.flatnonzero(base_mask)
        nb, n, horizon = len(self.base_columns), problem.n_joints, problem.horizon
        self.nb, self.n, self.horizon = nb, n, horizon
        self.n_variables = nb + n * horizon
        step_index = nb + n * np.arange(horizon)[:, None] + np.arange(n)[None, :]  # (T, N)

        # Upper-triangular Hessian pattern: base-base, base-step, step-step, step-(step+1) diagonal.
        rows, cols = [], []
        base_i, base_j = np.triu_indices(nb)
        rows.append(base_i.ravel())
        cols.append(base_j.ravel())
        rows.append(np.broadcast_to(np.arange(nb)[None, :, None], (horizon, nb, n)).ravel())
        cols.append(np.broadcast_to(step_index[:, None, :], (horizon, nb, n)).ravel())
        tri_i, tri_j = np.triu_indices(n)
        rows.append(step_index[:, tri_i].ravel())
        cols.append(step_index[:, tri_j].ravel())
        rows.append(step_index[:-1].ravel())
        cols.append(step_index[1:].ravel())
        row_index, col_index = np.concatenate(rows), np.concatenate(cols)
        order = sp.csc_matrix(
            (np.arange(1, len(row_index) + 1, dtype=float), (row_index, col_index)),
            shape=(self.n_variables, self.n_variables),
        )
        self._p_pattern = order
        self._p_order = order.data.astype(np.int64) - 1  # csc position k holds COO entry _p_order[k]
        self._tri = (tri_i, tri_j)
        self._base_tri = (base_i, base_j)

        # Constraints: positions (identity on dq), velocity differences / dt, and for a bound with
        # an acceleration limit the second differences / dt, velocity changes (dq_0 = 0, at rest
        # before the start).
        dt = problem.dt
        size = n * horizon
        blocks = [
            sp.identity(size, format="csc"),
            sp.diags([np.ones(size), -np.ones(size - n)], [0, -n], format="csc") / dt,
        ]
        if problem.bound.acceleration is not None:
            blocks.append(
                sp.diags(
                    [np.ones(size), -2.0 * np.ones(size - n), np.ones(size - 2 * n)], [0, -n, -2 * n], format="csc"
                )
                / dt
            )
        steps_block = sp.vstack(blocks, format="csc")
        self.A = sp.hstack([sp.csc_matrix((steps_block.shape[0], nb)), steps_block], format="csc")
        self.options = options
        self.solver: osqp.OSQP | None = None  # set up by the first solve
        self._duals = np.zeros(self.A.shape[0])  # the last QP's multipliers (warm start)

    def hessian_values(self, models: list[QuadraticModel], damping: float) -> np.ndarray:
        """CSC data of the upper-triangular Hessian: the terms' model blocks, summed in order, plus
        the damping ``damping |x|^2 / 2``."""
        base_block = _sum_blocks(m.hessian_base for m in models)
        base_block = (np.zeros((self.nb, self.nb)) if base_block is None else base_block) + damping * np.eye(self.nb)
        cross = _sum_blocks(m.hessian_cross for m in models)
        arm = _sum_blocks(m.hessian_steps for m in models)
        arm = np.zeros((self.horizon, self.n, self.n)) if arm is None else arm.copy()
        diagonal = _sum_blocks(m.hessian_diagonal for m in models)
        diagonal = np.zeros(self.horizon) if diagonal is None else diagonal
        arm[:, np.arange(self.n), np.arange(self.n)] += (diagonal + damping)[:, None]
        coupling = _sum_blocks(m.hessian_next for m in models)
        values = np.concatenate(
            [
                base_block[self._base_tri].ravel(),
                (np.zeros((self.horizon, self.nb, self.n)) if cross is None else cross).ravel(),
                arm[:, self._tri[0], self._tri[1]].ravel(),
                np.repeat(np.zeros(self.horizon - 1) if coupling is None else coupling, self.n),
            ]
        )
        return values[self._p_order]

    def gradient(self, models: list[QuadraticModel]) -> np.ndarray:
        """The QP's linear term: the terms' model gradients, summed in order, (nb + T N,)."""
        base = _sum_blocks(m.gradient_base for m in models)
        steps = _sum_blocks(m.gradient_steps for m in models)
        assert steps is not None, "every term has a gradient in the joint steps"
        return np.concatenate([np.zeros(self.nb) if base is None else base, steps.ravel()])

    def solve(
        self, hessian: np.ndarray, gradient: np.ndarray, lower: np.ndarray, upper: np.ndarray
    ) -> tuple[np.ndarray, int]:
        """Minimise 1/2 x'Px + g'x s.t. lower <= A x <= upper; returns (x, OSQP iterations)."""
        if self.solver is None:
            pattern = self._p_pattern.copy()
            pattern.data = hessian
            self.solver = osqp.OSQP()
            self.solver.setup(
                pattern,
                gradient,
                self.A,
                lower,
                upper,
                verbose=False,
                polishing=self.options.polishing,
                warm_starting=True,
                eps_abs=self.options.osqp_eps,
                eps_rel=self.options.osqp_eps,
                max_iter=self.options.osqp_max_iter,
                rho=self.options.osqp_rho,
                adaptive_rho_tolerance=self.options.osqp_adaptive_rho_tolerance,
            )
        else:
            self.solver.update(Px=hessian, q=gradient, l=lower, u=upper)
            # the step shrinks to zero as SQP converges while the active set persists: start the
            # primal at zero and the duals at the previous multipliers
            self.solver.warm_start(x=np.zeros(self.n_variables), y=self._duals)
        # OSQP 1.x prints "Polishing not needed ..." through Python's stdout on every solve with an
        # empty active set, even with verbose=False (osqp/osqp#785); an SQP solves hundreds of QPs.
        with contextlib.redirect_stdout(io.StringIO()):
            result = self.solver.solve(raise_error=False)
        self._duals = result.y
        status = result.info.status_val
        usable = (
            osqp.SolverStatus.OSQP_SOLVED,
            osqp.SolverStatus.OSQP_SOLVED_INACCURATE,
            osqp.SolverStatus.OSQP_MAX_ITER_REACHED,
        )
        if status not in usable or result.x is None or not np.all(np.isfinite(result.x)):
            raise SolverFailure(f"OSQP failed on the tracking QP: {result.info.status}")
        return result.x, int(result.info.iter)


def _sum_blocks(blocks: Iterable[np.ndarray | None]) -> np.ndarray | None:
    """The sum of the given blocks in order (None stands for zero; None if all are)."""
    total = None
    for block in blocks:
        if block is not None:
            total = block if total is None else total + block
    return total


def solve_sqp(
    problem: TrackingProblem,
    base_guess: np.ndarray,
    options: SqpOptions = SqpOptions(),
    q_guess: np.ndarray | None = None,
    stop_early: Callable[[np.ndarray, np.ndarray], bool] | None = None,
) -> SqpOutcome:
    """Optimise base and joint trajectory from ``base_guess`` (3,) = (x, y, yaw).

    The base coordinates that the robot cannot move (``robot.base_dofs``) stay at their guess.
    ``q_guess`` (T+1, N) initialises the joints (projected to the limits); default: q_start held.
    ``stop_early(base, q)``, called after each iteration, ends the run when it returns True
    (multi-start uses it to drop a run that joined another's basin); the outcome is then not
    ``converged``.
    """
    started = time.perf_counter()
    base, q = _start(problem, base_guess, q_guess)
    qp = _TrackingQp(problem, problem.robot.base_dofs, options)
    damping = options.initial_damping
    cost = problem.cost(base, q)
    history = [cost]
    qp_iterations = 0
    converged = False
    stopped_early = False
    iteration = 0
    at: Iterate | None = None
    for iteration in range(1, options.max_iterations + 1):  # noqa: B007 (the count is read after the loop)
        if at is None:
            at = problem.iterate(base, q, qp.base_columns)
        d_base, d_q, used = _qp_step(problem, qp, at, damping)
        qp_iterations += used
        predicted = _predicted_decrease(problem, at, d_base, d_q)
        if predicted <= options.relative_tolerance * cost:
            converged = True  # the model promises less than the tolerance
            break
        trial = _line_search(problem, qp, base, q, cost, d_base, d_q, predicted, options)
        if trial is None:  # the model is poor this far out (or the QP inexact): shorter steps
            damping *= 10.0
            if damping > options.max_damping:
                converged = True  # no descent even along tiny steps: a stationary point
                break
            continue
        trial_base, trial_q, trial_cost, length = trial
        damping = _adapted_damping(damping, length, (cost - trial_cost) / predicted)
        decrease = cost - trial_cost
        base, q, cost = trial_base, trial_q, trial_cost
        at = None
        history.append(cost)
        if decrease < options.relative_tolerance * cost:
            converged = True
            break
        if stop_early is not None and stop_early(base, q):
            stopped_early = True
            break
    return SqpOutcome(
        base=base,
        q=q,
        cost=cost,
        iterations=iteration,
        qp_iterations=qp_iterations,
        converged=converged,
        stopped_early=stopped_early,
        wall_time_s=time.perf_counter() - started,
        cost_history=tuple(history),
    )


def _start(
    problem: TrackingProblem, base_guess: np.ndarray, q_guess: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """The first iterate: base (3,) from the guess, q (T+1, N) from ``q_guess`` projected to the
    limits (q[0] = q_start), or q_start held."""
    horizon, n = problem.horizon, problem.n_joints
    base = np.asarray(base_guess, dtype=float).copy()
    if base.shape != (3,) or not np.all(np.isfinite(base)):
        raise ValueError(f"base guess must be 3 finite numbers (x, y, yaw), got {base_guess}")
    if q_guess is None:
        return base, np.tile(problem.q_start, (horizon + 1, 1))
    q = np.asarray(q_guess, dtype=float).copy()
    if q.shape != (horizon + 1, n):
        raise ValueError(f"q_guess must have shape ({horizon + 1}, {n}), got {q.shape}")
    q[0] = problem.q_start
    return base, project_to_limits(q, problem.dt, problem.bound)


def _qp_step(
    problem: TrackingProblem, qp: _TrackingQp, at: Iterate, damping: float
) -> tuple[np.ndarray, np.ndarray, int]:
    """The damped QP's step at ``at``: base step (nb,), joint-position steps (T, N), OSQP iterations.
    The bounds keep q + dq within the joint limits and its velocities within theirs."""
    bound = problem.bound
    models = [term.model(at) for term in problem.terms]
    velocity, acceleration = motion_from_rest(at.q, problem.dt)
    lows = [bound.lower - at.q[1:], -bound.velocity - velocity]
    ups = [bound.upper - at.q[1:], bound.velocity - velocity]
    if bound.acceleration is not None:  # as velocity changes per step, rad/s (module docstring)
        lows.append((-bound.acceleration - acceleration) * problem.dt)
        ups.append((bound.acceleration - acceleration) * problem.dt)
    bound_low = np.concatenate([low.ravel() for low in lows])
    bound_up = np.concatenate([up.ravel() for up in ups])
    step, used = qp.solve(qp.hessian_values(models, damping), qp.gradient(models), bound_low, bound_up)
    return step[: qp.nb], step[qp.nb :].reshape(problem.horizon, problem.n_joints), used


def _predicted_decrease(problem: TrackingProblem, at: Iterate, d_base: np.ndarray, d_q: np.ndarray) -> float:
    """J's decrease along the step predicted by the undamped model (the terms' parts in order)."""
    change = 0.0
    for term in problem.terms:
        for part in term.model_change(at, d_base, d_q):
            change += part
    return -change


def _line_search(
    problem: TrackingProblem,
    qp: _TrackingQp,
    base: np.ndarray,
    q: np.ndarray,
    cost: float,
    d_base: np.ndarray,
    d_q: np.ndarray,
    predicted: float,
    options: SqpOptions,
) -> tuple[np.ndarray, np.ndarray, float, float] | None:
    """Backtracking on the true J from step length 1, halving: the first (base, q, J, length) with
    sufficient decrease (Armijo, 1e-4 of the predicted one), the trajectory projected to the limits;
    None when no length in ``options.line_search_steps`` gives one."""
    length = 1.0
    for _ in range(options.line_search_steps):
        trial_base = base.copy()
        trial_base[qp.base_columns] += length * d_base
        trial_q = q.copy()
        trial_q[1:] += length * d_q
        trial_q = project_to_limits(trial_q, problem.dt, problem.bound)
        trial_cost = problem.cost(trial_base, trial_q)
        if trial_cost <= cost - 1e-4 * length * predicted:
            return trial_base, trial_q, trial_cost, length
        length *= 0.5
    return None


def _adapted_damping(damping: float, length: float, ratio: float) -> float:
    """Levenberg-Marquardt update of mu from the accepted step: a full step whose actual decrease
    is above 3/4 of the predicted one lowers it; a shortened step or a ratio below 1/4 raises it."""
    if length == 1.0 and ratio > 0.75:
        return max(damping / 3.0, 1e-9)
    if length < 1.0 or ratio < 0.25:
        return max(damping * 4.0, 1e-6)
    return damping
