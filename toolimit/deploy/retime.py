"""Time-parameterisation of a joint path under a robot's velocity, acceleration and jerk limits.

The path and its timing are one curve: a clamped cubic B-spline in time (``scipy.interpolate.BSpline``)
whose control points are the path's samples q_0..q_T, the first and the last repeated three times so
that the robot starts and stops at rest with zero acceleration. A path whose last step still moves
(a learnt motion ends where its episode ends, not at rest) faster than one step can stop is first
continued by braking at the acceleration limit
(:meth:`MotionBound.braking <toolimit.robots.motion_bound.MotionBound.braking>`): a real arm cannot
stop within a step, and stopping it on the path's last samples would slow the motion's end down (a
scythe's 0.83 s draw, measured: its last steps stretched, 1.17 s in all). Two properties of
B-splines make the limits hold everywhere, not only at the samples:

* **position**: on each span the curve is a convex combination of four consecutive control points,
  so no joint ever leaves the range of the samples around it: a path whose samples are within the
  position limits is never carried past one (an interpolating spline can overshoot there);
* **velocity, acceleration, jerk**: the k-th derivative is a B-spline whose control points are
  divided differences of the samples over the span durations; |derivative| never exceeds its
  largest control point.

Retiming chooses the span durations: start from the optimised step dt, stretch the spans on which
a derivative control point exceeds its limit (a stretch by f divides a k-th derivative control point
by f^k), repeat; a last uniform stretch covers what the rounds did not settle. Only slow spans are
slowed down, so the duration stays near the optimised one where the motion is gentle.

The curve approximates the samples rather than passing through them: at sample t it sits at
(q_{t-1} + 4 q_t + q_{t+1}) / 6 for equal spans, within a sixth of the second difference of q_t.
:attr:`RetimedPath.path_deviation` reports the largest gap.

Why not a time-parameterisation library (measured on the Panda trajectory of docs/cli.md#examples, 103 steps,
toppra 0.6.10 and ruckig 0.19.4 from PyPI): toppra is time-optimal under velocity and
acceleration limits only; on its own cubic spline through the samples its result passed a
position limit by 0.027 rad and reached 2.9x the jerk limit (finite differences at 1 kHz), it
replaces the demonstrated timing by the fastest one (6.9 s for a 21.5 s optimised motion, whose
timing the scene replay validated), and ``import toppra`` imports matplotlib, which this project
does not use. Ruckig's open-source version plans from one state to one target: intermediate
waypoints go to its remote cloud API (no network here), and it does not enforce position limits.
``benchmarks/export_retiming.py`` prints this module's figures.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BSpline

from toolimit.errors import PathOutsideLimits
from toolimit.robots.limits import JointLimits
from toolimit.robots.motion_bound import MotionBound

DEGREE = 3
#: Pieces per segment between two samples in the control polygon for a path whose samples do not
#: keep the limits at their own timing (see :func:`retime`).
DEFAULT_SUBDIVISIONS = 4
#: The most pieces per step: beyond, the corners are cut by less than rounding.
MAX_SUBDIVISIONS = 64
#: Rounds of local stretching before the final uniform stretch.
_MAX_ROUNDS = 200
#: Relative headroom kept under every limit: a control point within it of a limit (a path learnt on
#: its bound, a braking at the acceleration limit) is stretched to twice it below, so that the
#: samples are not judged over the limit by rounding.
_HEADROOM = 1e-9
METHOD = (
    "clamped cubic B-spline in time with the optimised joint samples as control points (ends repeated: "
    "rest to rest with zero acceleration); span durations stretched where a velocity, acceleration or "
    "jerk control point exceeded its limit (convex-hull bound: the limits hold at every instant); "
    "the final position is held after the end"
)


@dataclass(frozen=True)
class SampledTrajectory:
    """A joint trajectory on a uniform time grid: times (K,) s and (K, N) arrays per quantity (rad, s)."""

    times: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    def as_dict(self) -> dict[str, np.ndarray]:
        return {
            "position": self.position,
            "velocity": self.velocity,
            "acceleration": self.acceleration,
            "jerk": self.jerk,
        }


@dataclass(frozen=True)
class RetimedPath:
    """Joint positions q(t) (rad) of N joints, t in seconds from the start, within the limits used.

    Attributes:
        spline: the cubic B-spline q(t), t in [0, duration].
        duration: s, from rest to rest.
        path_deviation: largest |q(t_k) - q_k| over the path's samples and joints (rad), t_k the
            sample's Greville abscissa (where its weight peaks).
        lowest, highest: (N,) rad, each joint's smallest and largest sample: the curve stays within
            them (positions are clipped to them, which only removes rounding, of order 1e-16 rad).
        subdivisions: pieces per step between samples the curve was built with.
        braking_steps: samples added after the path's last one to brake it (one per step) to a speed
            from which its rest at the end stops within one step.
    """

    spline: BSpline
    duration: float
    path_deviation: float
    lowest: np.ndarray
    highest: np.ndarray
    subdivisions: int
    braking_steps: int = 0

    def derivative(self, times: np.ndarray, order: int) -> np.ndarray:
        """(K, N) d^order q / dt^order at ``times`` (K,) s; the final position is held after the end."""
        times = np.asarray(times, dtype=float)
        values = self.spline(np.clip(times, 0.0, self.duration), nu=order)
        after = times > self.duration
        values[after] = self.spline(self.duration) if order == 0 else 0.0
        return np.clip(values, self.lowest, self.highest) if order == 0 else values

    def sample(self, rate: float) -> SampledTrajectory:
        """Samples every 1/rate s (rate in Hz) from 0 to the first grid time at or after the end."""
        if not rate > 0:
            raise ValueError(f"rate must be positive (Hz), got {rate}")
        count = int(np.ceil(self.duration * rate - 1e-9)) + 1
        times = np.arange(count) / rate
        return SampledTrajectory(times, *(self.derivative(times, order) for order in range(4)))


def check_path_positions(q: np.ndarray, dt: float, limits: JointLimits) -> None:
    """Raise :class:`PathOutsideLimits` naming the sample of q (T+1, N) farthest outside a position limit."""
    below = limits.position_lower - q
    above = q - limits.position_upper
    excess = np.maximum(below, above)
    if not (excess > 0).any():
        return
    k, j = np.unravel_index(np.argmax(excess), excess.shape)
    bound = limits.position_lower[j] if below[k, j] > 0 else limits.position_upper[j]
    raise PathOutsideLimits(
        f"{limits.joint_names[j]} position {q[k, j]:.6g} rad at sample {k} (t = {k * dt:.4f} s of the optimised "
        f"trajectory) is beyond its limit {bound:.6g} rad by {excess[k, j]:.3g} rad "
        f"(range [{limits.position_lower[j]:.6g}, {limits.position_upper[j]:.6g}]); no retiming can fix a path "
        f"point outside the position limits ({int((excess > 0).any(axis=1).sum())} of {len(q)} samples are outside)"
    )


def subdivisions_for(q: np.ndarray, dt: float, limits: JointLimits) -> int:
    """1 for a path q (T+1, N) whose samples keep ``limits``' range, velocity and acceleration at
    their own timing from rest (a motion learnt within them): the samples themselves are the
    control points and the curve keeps their timing, within a sixth of a step's velocity change of
    each sample; else :data:`DEFAULT_SUBDIVISIONS`."""
    return 1 if MotionBound.of_limits(limits).holds(q, dt) else DEFAULT_SUBDIVISIONS


def retime(q: np.ndarray, dt: float, limits: JointLimits, subdivisions: int | None = None) -> RetimedPath:
    """Time the joint path q (T+1, N) rad, sampled every ``dt`` s, within ``limits`` (see the module docstring).

    ``subdivisions``: the control points are the straight segments between samples cut into this
    many pieces; more pieces keep the curve closer to the samples (corners are cut less) at the
    price of a slower turn at each corner. None: :func:`subdivisions_for` the path.

    Raises :class:`PathOutsideLimits` if a sample is outside the position limits, ValueError for a
    malformed path.
    """
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or len(q) < 2 or q.shape[1] != len(limits.joint_names):
        raise ValueError(f"q must have shape (T+1, {len(limits.joint_names)}) with T >= 1, got {q.shape}")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive number of seconds, got {dt}")
    if not np.all(np.isfinite(q)):
        raise ValueError("q contains non-finite values")
    check_path_positions(q, dt, limits)
    braking = MotionBound.of_limits(limits).braking(q, dt)
    q = np.concatenate([q, braking])
    if subdivisions is None:
        subdivisions = subdivisions_for(q, dt, limits)
    if not (isinstance(subdivisions, (int, np.integer)) and subdivisions >= 1):
        raise ValueError(f"subdivisions must be a positive integer, got {subdivisions}")
    fractions = np.arange(subdivisions) / subdivisions
    polyline = np.concatenate(
        [(q[:-1, None] + fractions[:, None] * np.diff(q, axis=0)[:, None]).reshape(-1, q.shape[1]), q[-1:]]
    )
    control = np.concatenate([np.repeat(q[:1], DEGREE - 1, axis=0), polyline, np.repeat(q[-1:], DEGREE - 1, axis=0)])
    bounds = (limits.velocity, limits.acceleration, limits.jerk)
    spans = np.full(len(control) - DEGREE, dt / subdivisions)
    for _ in range(_MAX_ROUNDS):
        stretch = _stretch_per_span(control, spans, bounds)
        if np.all(stretch == 1.0):
            break
        spans = spans * stretch
    else:  # what the local rounds left: one uniform stretch, exact since every control point scales alike
        spline = _spline(control, spans)
        worst = max(_ratios(spline, order, bound).max() ** (1.0 / order) for order, bound in enumerate(bounds, 1))
        spans = spans * max(1.0, worst) * (1.0 + _HEADROOM)
    spline = _spline(control, spans)
    greville = np.array([spline.t[i + 1 : i + 1 + DEGREE].mean() for i in range(len(control))])
    at_samples = greville[DEGREE - 1 : DEGREE - 1 + len(polyline) : subdivisions]
    deviation = np.abs(spline(at_samples) - q).max()
    return RetimedPath(
        spline=spline,
        duration=float(spline.t[-1]),
        path_deviation=float(deviation),
        lowest=q.min(axis=0),
        highest=q.max(axis=0),
        subdivisions=int(subdivisions),
        braking_steps=len(braking),
    )


def _spline(control: np.ndarray, spans: np.ndarray) -> BSpline:
    """The clamped cubic B-spline with these control points (n, N) and interior span durations (n - 3,)."""
    inner = np.concatenate([[0.0], np.cumsum(spans)])
    knots = np.concatenate([np.zeros(DEGREE), inner, np.full(DEGREE, inner[-1])])
    return BSpline(knots, control, DEGREE)


def _ratios(spline: BSpline, order: int, bound: np.ndarray) -> np.ndarray:
    """Per control point of the ``order``-th derivative: the largest |value| / limit over the joints."""
    coefficients = spline.derivative(order).c[: len(spline.c) - order]
    return np.max(np.abs(coefficients) / bound, axis=1)


def _stretch_per_span(control: np.ndarray, spans: np.ndarray, bounds: tuple[np.ndarray, ...]) -> np.ndarray:
    """Factor (>= 1) per span that brings every derivative control point over its limit, or within
    rounding of it, just under it.

    The i-th control point of the k-th derivative depends on the knots t_{i+1}..t_{i+k+3}, i.e. on
    the interior spans i-2 .. i+k-1 (the clamped ends' zero spans aside); stretching all of them by
    f divides it by f^k.
    """
    spline = _spline(control, spans)
    stretch = np.ones_like(spans)
    for order, bound in enumerate(bounds, 1):
        ratios = _ratios(spline, order, bound)
        for i in np.nonzero(ratios > 1.0 - _HEADROOM)[0]:  # on a limit: rounding may carry a sample past it
            first, last = max(0, i - DEGREE + 1), min(len(spans), i + order)
            factor = (ratios[i] / (1.0 - 2.0 * _HEADROOM)) ** (1.0 / order)
            stretch[first:last] = np.maximum(stretch[first:last], factor)
    return stretch
