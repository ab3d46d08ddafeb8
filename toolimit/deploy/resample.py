"""A smooth rest-to-rest interpolant of control-rate joint samples, resampled at the robot's rate.

Interpolant: ``scipy.interpolate.make_interp_spline`` of degree 5 (quintic) through every
control-rate sample, with zero velocity and zero acceleration at both ends (the robot starts and
stops at rest, as a real controller requires). Position, velocity, acceleration and jerk are the
spline and its analytic derivatives: C^4 continuous, so jerk is continuous inside the motion.
Beyond the last sample the robot holds the final position (all derivatives 0).

Stretching time by a factor ``s`` gives the same path with velocity / s, acceleration / s^2 and
jerk / s^3 (the interpolant commutes with time scaling).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BSpline, make_interp_spline

SPLINE_DEGREE = 5
INTERPOLANT = ("quintic interpolating B-spline (scipy make_interp_spline, k=5) through every control-rate "
               "sample, zero velocity and acceleration at both ends; the final position is held after the end")


@dataclass(frozen=True)
class JointSpline:
    """Joint positions q(t) (rad) of N joints, t in seconds from the first sample."""

    spline: BSpline
    duration: float
    final_position: np.ndarray

    def derivative(self, times: np.ndarray, order: int) -> np.ndarray:
        """(K, N) d^order q / dt^order at ``times`` (K,) s; held constant after the end."""
        times = np.asarray(times, dtype=float)
        inside = np.clip(times, 0.0, self.duration)
        values = self.spline(inside, nu=order)
        after = times > self.duration
        values[after] = self.final_position if order == 0 else 0.0
        return values


def fit_joint_spline(q: np.ndarray, dt: float) -> JointSpline:
    """Interpolate samples q (T+1, N) rad taken every ``dt`` s (see the module docstring)."""
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or len(q) < 2:
        raise ValueError(f"q must have shape (T+1, N) with T >= 1, got {q.shape}")
    if not dt > 0:
        raise ValueError(f"dt must be positive, got {dt}")
    times = dt * np.arange(len(q))
    rest = [(1, np.zeros(q.shape[1])), (2, np.zeros(q.shape[1]))]
    spline = make_interp_spline(times, q, k=SPLINE_DEGREE, bc_type=(rest, rest), axis=0)
    return JointSpline(spline=spline, duration=float(times[-1]), final_position=q[-1].copy())


@dataclass(frozen=True)
class SampledTrajectory:
    """A joint trajectory on a uniform time grid: times (K,) s and (K, N) arrays per quantity."""

    times: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    def as_dict(self) -> dict[str, np.ndarray]:
        return {"position": self.position, "velocity": self.velocity,
                "acceleration": self.acceleration, "jerk": self.jerk}


def resample(spline: JointSpline, rate: float) -> SampledTrajectory:
    """Samples every 1/rate s from 0 to the first grid time at or after the end (rate in Hz)."""
    if not rate > 0:
        raise ValueError(f"rate must be positive (Hz), got {rate}")
    count = int(np.ceil(spline.duration * rate - 1e-9)) + 1
    times = np.arange(count) / rate
    return SampledTrajectory(times, *(spline.derivative(times, order) for order in range(4)))
