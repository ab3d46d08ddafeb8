"""Export an optimised joint trajectory for open-loop execution on a real robot.

Input: ``DIR/trajectory.npz`` written by trajectory optimisation: ``q`` (T+1, N) rad, ``v`` (T, N)
rad/s with ``q[t] = q[t-1] + dt v[t-1]``, ``base`` (3,) = (x m, y m, yaw rad) world placement of
the robot base, ``joint_names`` (N,), ``dt`` (s).

Output (only if every limit check passes; each file written atomically):

* ``joint_trajectory_control_rate.csv``: the samples q_t at t * dt * time_scale;
* ``joint_trajectory_resampled.csv``: the smooth interpolant (:mod:`toolimit.deploy.resample`)
  sampled at ``rate`` Hz, the commands to stream to the robot;
* ``joint_trajectory.json``: joint names, rates, units, the limits used, every check's worst sample,
  the interpolant, the time scale and the base placement.

CSV: header ``time_s`` then the joint names; one row per sample; positions in rad.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from toolimit.artifacts import atomic_path
from toolimit.deploy.limits import UNITS, JointLimits, QuantityCheck, check_samples, published_limits
from toolimit.deploy.resample import INTERPOLANT, SampledTrajectory, fit_joint_spline, resample

CONTROL_CSV = "joint_trajectory_control_rate.csv"
RESAMPLED_CSV = "joint_trajectory_resampled.csv"
SUMMARY_JSON = "joint_trajectory.json"
DEFAULT_RATE_HZ = 1000.0
_VELOCITY_CONSISTENCY_TOL = 1e-6  # rad/s: |v - diff(q)/dt| allowed in trajectory.npz
_TIME_SCALE_STEP = 1e-3  # resolution of the suggested minimal time scale


@dataclass(frozen=True)
class JointTrajectory:
    """A trajectory.npz: q (T+1, N) rad, v (T, N) rad/s, base (3,) (m, m, rad), joint names, dt s."""

    q: np.ndarray
    v: np.ndarray
    base: np.ndarray
    joint_names: tuple[str, ...]
    dt: float


def load_trajectory(directory: str | Path) -> JointTrajectory:
    """Read and validate ``directory/trajectory.npz`` (errors name the file and the field)."""
    path = Path(directory) / "trajectory.npz"
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file (expected the output of `toolimit trajopt`)")
    with np.load(path, allow_pickle=False) as data:
        missing = [key for key in ("q", "v", "base", "joint_names", "dt") if key not in data]
        if missing:
            raise ValueError(f"{path}: missing field(s) {', '.join(missing)}")
        q = np.asarray(data["q"], dtype=float)
        v = np.asarray(data["v"], dtype=float)
        base = np.asarray(data["base"], dtype=float)
        joint_names = tuple(str(name) for name in np.atleast_1d(data["joint_names"]))
        dt = float(data["dt"])
    if q.ndim != 2 or len(q) < 2:
        raise ValueError(f"{path}: q must have shape (T+1, N) with T >= 1, got {q.shape}")
    n_steps, n_joints = len(q) - 1, q.shape[1]
    if v.shape != (n_steps, n_joints):
        raise ValueError(f"{path}: v must have shape {(n_steps, n_joints)} to match q {q.shape}, got {v.shape}")
    if base.shape != (3,):
        raise ValueError(f"{path}: base must have shape (3,), got {base.shape}")
    if len(joint_names) != n_joints:
        raise ValueError(f"{path}: joint_names has {len(joint_names)} names for {n_joints} joints in q")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"{path}: dt must be a positive number of seconds, got {dt}")
    for name, array in (("q", q), ("v", v), ("base", base)):
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{path}: {name} contains non-finite values")
    mismatch = np.abs(np.diff(q, axis=0) / dt - v)
    if mismatch.max() > _VELOCITY_CONSISTENCY_TOL:
        t, j = np.unravel_index(np.argmax(mismatch), mismatch.shape)
        raise ValueError(f"{path}: v[{t}, {j}] differs from (q[{t + 1}] - q[{t}]) / dt by {mismatch[t, j]:.3g} rad/s")
    return JointTrajectory(q=q, v=v, base=base, joint_names=joint_names, dt=dt)


class LimitViolation(ValueError):
    """The trajectory would exceed a published limit; nothing was written.

    Attributes: ``checks`` (every quantity's worst sample), ``minimal_time_scale`` (a time scale
    at which the checks pass, or None when a position limit is exceeded, which slowing down cannot fix).
    """

    def __init__(self, checks: list[QuantityCheck], minimal_time_scale: float | None,
                 samples_within_position_limits: bool = False) -> None:
        self.checks = checks
        self.minimal_time_scale = minimal_time_scale
        failed = [check for check in checks if not check.passed]
        message = "; ".join(check.describe() for check in failed)
        if minimal_time_scale is not None:
            message += (f"; a time scale of at least {minimal_time_scale:.3f} (--time-scale "
                        f"{minimal_time_scale:.3f}, slower) would pass")
        elif any(check.quantity == "position" for check in failed):
            message += "; slowing down cannot fix a position limit"
            if samples_within_position_limits:
                message += (" (every control-rate sample is within its limits: the smooth interpolant overshoots "
                            "between samples that touch a limit)")
        super().__init__(f"refusing to export: {message}")


@dataclass(frozen=True)
class ExportPlan:
    """The checked trajectory: the resampled commands and each quantity's worst sample."""

    trajectory: JointTrajectory
    limits: JointLimits
    time_scale: float
    rate: float
    samples: SampledTrajectory
    checks: list[QuantityCheck]

    @property
    def passed(self) -> bool:
        return all(check.passed for check in self.checks)


def check_trajectory(trajectory: JointTrajectory, limits: JointLimits, rate: float = DEFAULT_RATE_HZ,
                     time_scale: float = 1.0) -> ExportPlan:
    """Interpolate with the trajectory's time stretched by ``time_scale`` (> 1 slows down; the step
    becomes dt * time_scale), resample at ``rate`` Hz, check."""
    if tuple(trajectory.joint_names) != limits.joint_names:
        raise ValueError(f"trajectory joints {list(trajectory.joint_names)} do not match "
                         f"{limits.robot}'s joints {list(limits.joint_names)}")
    if not (math.isfinite(time_scale) and time_scale > 0):
        raise ValueError(f"time scale must be a positive number, got {time_scale}")
    spline = fit_joint_spline(trajectory.q, trajectory.dt * time_scale)
    samples = resample(spline, rate)
    checks = check_samples(limits, samples.times, samples.as_dict())
    return ExportPlan(trajectory, limits, time_scale, rate, samples, checks)


def minimal_time_scale(trajectory: JointTrajectory, limits: JointLimits, rate: float = DEFAULT_RATE_HZ) -> float | None:
    """The smallest time scale (to 1e-3) at which every check passes; None if a position limit fails.

    Velocity scales as 1/s, acceleration 1/s^2, jerk 1/s^3, which gives the estimate; it is then
    verified on the resampled grid and raised step by step if the grid sees a slightly larger peak.
    """
    plan = check_trajectory(trajectory, limits, rate, 1.0)
    ratio = {check.quantity: check.ratio for check in plan.checks}
    if ratio["position"] > 0:
        return None
    estimate = max(1.0, ratio["velocity"], ratio["acceleration"] ** 0.5, ratio["jerk"] ** (1.0 / 3.0))
    scale = math.ceil(estimate / _TIME_SCALE_STEP) * _TIME_SCALE_STEP
    for _ in range(100):
        if check_trajectory(trajectory, limits, rate, scale).passed:
            return scale
        scale += _TIME_SCALE_STEP
    return None


def _csv(times: np.ndarray, positions: np.ndarray, joint_names: tuple[str, ...]) -> str:
    buffer = io.StringIO()
    np.savetxt(buffer, np.column_stack([times, positions]), delimiter=",", fmt="%.9f",
               header=",".join(("time_s",) + tuple(joint_names)), comments="")
    return buffer.getvalue()


def export_trajectory(trajectory: JointTrajectory, robot: str, out_dir: str | Path, rate: float = DEFAULT_RATE_HZ,
                      time_scale: float = 1.0, source: str | None = None) -> ExportPlan:
    """Check ``trajectory`` against ``robot``'s published limits and write the three files to ``out_dir``.

    Raises :class:`LimitViolation` (nothing written) if a limit is exceeded, ValueError for an
    unsupported robot or mismatched joints.
    """
    limits = published_limits(robot)
    plan = check_trajectory(trajectory, limits, rate, time_scale)
    if not plan.passed:
        samples_inside = bool(np.all((trajectory.q >= limits.position_lower) & (trajectory.q <= limits.position_upper)))
        raise LimitViolation(plan.checks, minimal_time_scale(trajectory, limits, rate), samples_inside)
    control_dt = trajectory.dt * time_scale
    control_times = control_dt * np.arange(len(trajectory.q))
    documents = {
        CONTROL_CSV: _csv(control_times, trajectory.q, trajectory.joint_names),
        RESAMPLED_CSV: _csv(plan.samples.times, plan.samples.position, trajectory.joint_names),
    }
    summary = {
        "robot": robot,
        "joint_names": list(trajectory.joint_names),
        "control_rate_hz": 1.0 / control_dt,
        "resampled_rate_hz": rate,
        "time_scale": time_scale,
        "duration_s": float(control_times[-1]),
        "n_control_samples": len(control_times),
        "n_resampled_samples": len(plan.samples.times),
        "units": {"time": "s", **UNITS},
        "interpolation": INTERPOLANT,
        "limits": limits.as_dict(),
        "checks": {check.quantity: check.as_dict() for check in plan.checks},
        "base": {"x_m": float(trajectory.base[0]), "y_m": float(trajectory.base[1]),
                 "yaw_rad": float(trajectory.base[2]),
                 "frame": "world; place the robot base here before execution"},
        "files": {"control_rate_csv": CONTROL_CSV, "resampled_csv": RESAMPLED_CSV},
        "source": source,
    }
    documents[SUMMARY_JSON] = json.dumps(summary, indent=2) + "\n"
    out_dir = Path(out_dir)
    with contextlib.ExitStack() as stack:  # every file is complete before the first is renamed into place
        for name, text in documents.items():
            stack.enter_context(atomic_path(out_dir / name)).write_text(text)
    return plan
