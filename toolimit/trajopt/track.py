"""Multi-start tracking: base initialisations around the targets, one SQP per start, best kept.

Base guesses (the benchmark's scheme, PROBLEM.md, generalised to any count): c = mean of the
target positions' x-y; guess k stands at radius ``start_radius`` from c at angle
``atan2(-c_y, -c_x) + 2 pi k / n`` (guess 0 towards the world origin), turned so that the tool
tip at ``q_start`` (base at the origin) lies on the ray from the base towards c. Starts beyond
``ring_starts`` are drawn from ``rng``: radius uniform in [0.3, 1.0] m, any angle, the same yaw
rule plus a uniform offset in [-pi/4, pi/4]. For a robot whose base moves along x only
(``planar3``), the guesses are ``c_x + offset`` with offsets evenly spread in
[-start_radius, start_radius] (then uniform in [-1, 1] m for random ones), y and yaw at 0.

Joint initialisations (``TrackOptions.initialisations``): ``"hold"`` starts every run from the
robot holding ``q_start`` (as PROBLEM.md's reference does); ``"rollout"`` from a greedy
differential-IK rollout along the targets (:mod:`toolimit.trajopt.initial_guess`). Neither
dominates: on the benchmark problem (8 starts, J of the best) hold / rollout give 6.3587 / 6.3587
(video1, time scale 1), 2.270 / 1.808 (video1, scale 4), 2.115 / 1.257 (video1, scale 5), 3.9015 /
3.9015 (example, scale 1), 0.907 / 1.045 (example, scale 4), 0.781 / 0.810 (example, scale 5), so
running both (twice the work) keeps the better everywhere there.

A roll-symmetric tool (``ToolSpec.roll_symmetric``) is tracked against the targets and against
the targets turned by pi about the tool axis; the better is kept.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from toolimit.errors import BaseInsideFootprint, InvalidSetting
from toolimit.progress import progress_bar
from toolimit.robots import RobotModel
from toolimit.robots.motion_bound import MotionBound
from toolimit.tools import wrap_angle
from toolimit.trajopt.initial_guess import ik_rollout
from toolimit.trajopt.problem import PoseTargets, TrackingProblem, TrackingWeights
from toolimit.trajopt.result import TrackingStatistics, TrajectoryResult, UpsideDownTracking
from toolimit.trajopt.sqp import SqpOptions, SqpOutcome, solve_sqp

#: Joint-trajectory initialisations of a run (see the module docstring).
INITIALISATIONS = ("hold", "rollout")


@dataclass(frozen=True)
class TrackOptions:
    """Settings of :func:`track`.

    Attributes:
        weights: cost weights (:class:`~toolimit.trajopt.problem.TrackingWeights`).
        sqp: SQP and OSQP settings.
        starts: number of base initialisations (8 = the benchmark's ring).
        ring_starts: how many of them lie on the deterministic ring (the rest are random).
        start_radius: ring radius around the targets' centre, metres.
        time_scale: slow-down factor, dt = time_scale / fps.
        q_start: (N,) start configuration, radians; ``robot.q_neutral`` when None.
        footprints: (M, 5) ground rectangles (centre x, y, half-length, half-width, yaw; metres,
            radians) where the base may not stand; a solution inside one is discarded.
        merge_distance: a run whose base (m, rad) and joints (rad) all come within this distance
            of an already converged run stops there (same basin; saves time); 0 disables it.
        initialisations: joint initialisations run from every base guess, among ``"hold"``
            (q_start held) and ``"rollout"`` (greedy differential IK); see the module docstring.
        progress: show a progress bar over the starts.
        bound: the joints' range, velocity and acceleration bounds; ``MotionBound.of(robot)`` when
            None (:class:`~toolimit.trajopt.problem.TrackingProblem`).
    """

    weights: TrackingWeights = TrackingWeights()
    sqp: SqpOptions = SqpOptions()
    starts: int = 8
    ring_starts: int = 8
    start_radius: float = 0.6
    time_scale: float = 1.0
    q_start: np.ndarray | None = None
    footprints: np.ndarray | None = field(default=None)
    merge_distance: float = 0.02
    initialisations: tuple[str, ...] = INITIALISATIONS
    progress: bool = False
    bound: MotionBound | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.starts, (int, np.integer)) and self.starts >= 1):
            raise InvalidSetting("starts", f"must be an integer >= 1, got {self.starts}")
        if not (np.isfinite(self.time_scale) and self.time_scale > 0):
            raise InvalidSetting("time_scale", f"must be positive, got {self.time_scale}")
        if not self.start_radius > 0:
            raise InvalidSetting("start_radius", f"must be positive, got {self.start_radius}")
        unknown = set(self.initialisations) - set(INITIALISATIONS)
        if not self.initialisations or unknown:
            raise InvalidSetting(
                "initialisations", f"must be a non-empty subset of {INITIALISATIONS}, got {self.initialisations}"
            )


def base_guesses(
    robot: RobotModel,
    targets: PoseTargets,
    count: int = TrackOptions.starts,
    radius: float = TrackOptions.start_radius,
    ring: int = TrackOptions.ring_starts,
    rng: np.random.Generator | None = None,
    q_start: np.ndarray | None = None,
) -> np.ndarray:
    """(count, 3) base initialisations (x, y, yaw) around the targets (see the module docstring)."""
    centre = targets.positions[:, :2].mean(axis=0)
    ring = min(ring, count)
    extra = count - ring
    if extra and rng is None:
        raise ValueError("random base guesses beyond the ring need an rng")
    if not robot.base_dofs[1]:  # base moves along x only
        offsets = np.linspace(-radius, radius, ring) if ring > 1 else np.zeros(ring)
        if extra and rng is not None:  # (rng is given whenever extra > 0: checked above)
            offsets = np.concatenate([offsets, rng.uniform(-1.0, 1.0, extra)])
        guesses = np.zeros((count, 3))
        guesses[:, 0] = centre[0] + offsets
        return guesses
    tip0 = robot.tool_pose(robot.q_neutral if q_start is None else q_start, np.zeros(3))[0]
    angles = np.arctan2(-centre[1], -centre[0]) + 2 * np.pi * np.arange(ring) / max(ring, 1)
    radii = np.full(ring, radius)
    yaw_offsets = np.zeros(ring)
    if extra and rng is not None:
        angles = np.concatenate([angles, rng.uniform(-np.pi, np.pi, extra)])
        radii = np.concatenate([radii, rng.uniform(0.3, 1.0, extra)])
        yaw_offsets = np.concatenate([yaw_offsets, rng.uniform(-np.pi / 4, np.pi / 4, extra)])
    positions = centre + radii[:, None] * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    towards = centre - positions
    yaw = np.arctan2(towards[:, 1], towards[:, 0]) - np.arctan2(tip0[1], tip0[0]) + yaw_offsets
    if not robot.base_dofs[2]:
        yaw = np.zeros(count)
    return np.column_stack([positions, wrap_angle(yaw)])


def base_in_footprints(base: np.ndarray, footprints: np.ndarray | None) -> int | None:
    """Index of the first footprint (M, 5) containing the base point (x, y), or None."""
    if footprints is None or len(footprints) == 0:
        return None
    footprints = np.asarray(footprints, dtype=float).reshape(-1, 5)
    offset = np.asarray(base[:2], dtype=float) - footprints[:, :2]
    c, s = np.cos(footprints[:, 4]), np.sin(footprints[:, 4])
    along = c * offset[:, 0] + s * offset[:, 1]
    across = -s * offset[:, 0] + c * offset[:, 1]
    inside = (np.abs(along) <= footprints[:, 2]) & (np.abs(across) <= footprints[:, 3])
    hits = np.flatnonzero(inside)
    return int(hits[0]) if hits.size else None


def track(
    robot: RobotModel,
    targets: PoseTargets,
    options: TrackOptions = TrackOptions(),
    rng: np.random.Generator | None = None,
    guesses: np.ndarray | None = None,
) -> TrajectoryResult:
    """Optimise base and joint trajectory to follow ``targets``; the best start is returned.

    ``guesses`` (S, 3) replaces the generated base initialisations. The result's
    :class:`~toolimit.trajopt.result.TrackingStatistics` hold the cost J and its terms, the best
    run's iterations, the cost of every run, merged and rejected counts, wall time. A result that
    tracks the tool upside down (``TrajectoryResult.upside_down``) warns
    :class:`~toolimit.trajopt.result.UpsideDownTracking`.
    """
    started = time.perf_counter()
    dt = options.time_scale / targets.fps
    if guesses is None:
        guesses = base_guesses(
            robot, targets, options.starts, options.start_radius, options.ring_starts, rng, options.q_start
        )
    guesses = np.atleast_2d(np.asarray(guesses, dtype=float))
    variants = [targets, targets.rotated_about_tool_z(np.pi)] if robot.tool.roll_symmetric else [targets]
    runs: list[_Run] = []
    rejected = 0
    merged = 0
    start_costs: list[float | None] = []  # per (variant, initialisation, start); None: in a footprint
    total = len(variants) * len(options.initialisations) * len(guesses)
    with progress_bar(total=total, desc=f"trajopt {robot.name}", disable=not options.progress) as bar:
        for variant_index, variant in enumerate(variants):
            problem = TrackingProblem(robot, variant, dt, options.q_start, options.weights, options.bound)
            finished: list[SqpOutcome] = []
            for initialisation in options.initialisations:
                for start_index, guess in enumerate(guesses):
                    q_guess = ik_rollout(problem, guess) if initialisation == "rollout" else None
                    outcome = solve_sqp(
                        problem, guess, options.sqp, q_guess=q_guess, stop_early=_joins(finished, options)
                    )
                    bar.update()
                    if outcome.converged:
                        finished.append(outcome)
                    merged += outcome.stopped_early
                    inside = base_in_footprints(outcome.base, options.footprints) is not None
                    rejected += inside
                    start_costs.append(None if inside else outcome.cost)
                    if not inside:
                        runs.append(_Run(variant_index, start_index, initialisation, outcome, problem))
    if not runs:
        raise BaseInsideFootprint(f"every one of the {rejected} solutions puts the robot base inside a scene element")
    run = min(runs, key=lambda run: run.outcome.cost)
    best, problem = run.outcome, run.problem
    statistics = TrackingStatistics(
        cost=best.cost,
        initial_cost=best.cost_history[0],
        cost_terms=problem.cost_terms(best.base, best.q),
        iterations=best.iterations,
        qp_iterations=best.qp_iterations,
        converged=best.converged,
        start_index=run.start_index,
        roll_variant=run.variant_index,
        initialisation=run.initialisation,
        start_costs=tuple(start_costs),
        starts_rejected_in_footprints=rejected,
        starts_merged=merged,
        wall_time_s=time.perf_counter() - started,
        best_start_wall_time_s=best.wall_time_s,
        weights=options.weights,
    )
    result = evaluate_trajectory(robot, problem.targets, best.base, best.q, dt, options.time_scale, statistics)
    if result.upside_down:
        warnings.warn(UpsideDownTracking.of(result), stacklevel=2)
    return result


@dataclass(frozen=True)
class _Run:
    """One finished SQP run whose base stands outside every footprint: where it started and its outcome."""

    variant_index: int  # 0: the targets, 1: turned by pi about the tool axis
    start_index: int  # row of the base guesses
    initialisation: str  # one of INITIALISATIONS
    outcome: SqpOutcome
    problem: TrackingProblem


def _joins(finished: list[SqpOutcome], options: TrackOptions) -> Callable[[np.ndarray, np.ndarray], bool]:
    """A ``stop_early`` test: the run's base and joints came within ``options.merge_distance`` of a
    converged run (base x, y in m, yaw modulo 2 pi in rad, joints in rad), so it is in that run's
    basin and would converge to the same optimum."""

    def joins(base: np.ndarray, q: np.ndarray) -> bool:
        if options.merge_distance <= 0:
            return False
        for other in finished:
            yaw_gap = abs(float(wrap_angle(base[2] - other.base[2])))
            gap = max(float(np.abs(base[:2] - other.base[:2]).max()), yaw_gap, float(np.abs(q - other.q).max()))
            if gap < options.merge_distance:
                return True
        return False

    return joins


def evaluate_trajectory(
    robot: RobotModel,
    targets: PoseTargets,
    base: np.ndarray,
    q: np.ndarray,
    dt: float,
    time_scale: float,
    statistics: TrackingStatistics | None,
) -> TrajectoryResult:
    """Errors, limit margins and velocity ratios of a trajectory q (T+1, N) at ``base`` (3,), with
    the ``statistics`` of the solve that found it (None for a trajectory made another way)."""
    positions, rotations = robot.tool_poses(q[1:], base)
    position_error = np.linalg.norm(positions - targets.positions, axis=1)
    relative = np.swapaxes(targets.rotations, 1, 2) @ rotations
    rotation_error = np.array([np.linalg.norm(pin.log3(r)) for r in relative])
    v = np.diff(q, axis=0) / dt
    return TrajectoryResult(
        robot=robot.name,
        tool=robot.tool.name,
        joint_names=robot.joint_names,
        q=q,
        v=v,
        base=np.asarray(base, dtype=float),
        dt=dt,
        time_scale=time_scale,
        position_error=position_error,
        rotation_error=rotation_error,
        limit_margin=np.minimum(q - robot.lower, robot.upper - q),
        velocity_ratio=np.abs(v) / robot.velocity_limit,
        statistics=statistics,
    )
