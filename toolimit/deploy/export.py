"""Export an optimised joint trajectory for open-loop execution on a real robot.

Input: ``DIR/trajectory.npz`` written by trajectory optimisation: ``q`` (T+1, N) rad, ``v`` (T, N)
rad/s with ``q[t] = q[t-1] + dt v[t-1]``, ``base`` (3,) = (x m, y m, yaw rad) world placement of
the robot base, ``joint_names`` (N,), ``dt`` (s).

The joint path q is retimed within the robot's published velocity, acceleration and jerk limits
(:mod:`toolimit.deploy.retime`: slowed down only where a limit requires it, never carried past a
position limit) and sampled at ``rate`` Hz. Only a path sample outside a position limit is refused.

Output (each file written atomically, both complete before either is renamed into place):

* ``joint_trajectory.csv``: the commands to stream to the robot, every 1/rate s from rest to rest;
  header ``time_s`` then the joint names, positions in rad;
* ``joint_trajectory.json``: joint names, rate, units, exported and optimised durations, the largest
  gap between the exported path and the optimised samples, the limits used, every quantity's
  worst sample, the retiming method and the base placement.
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
from toolimit.deploy.limits import (
    UNITS,
    JointLimits,
    QuantityCheck,
    check_samples,
    published_limits,
)
from toolimit.deploy.retime import (
    DEFAULT_SUBDIVISIONS,
    METHOD,
    RetimedPath,
    SampledTrajectory,
    retime,
)
from toolimit.errors import InputError
from toolimit.trajopt.result import JointTrajectory

TRAJECTORY_CSV = "joint_trajectory.csv"
SUMMARY_JSON = "joint_trajectory.json"
DEFAULT_RATE_HZ = 1000.0


@dataclass(frozen=True)
class ExportPlan:
    """The retimed trajectory: the samples to stream and each quantity's worst sample against its limit."""

    trajectory: JointTrajectory
    limits: JointLimits
    rate: float
    path: RetimedPath
    samples: SampledTrajectory
    checks: list[QuantityCheck]

    @property
    def optimised_duration(self) -> float:
        """Duration of the optimised trajectory, s (T dt)."""
        return self.trajectory.dt * (len(self.trajectory.q) - 1)


def plan_export(
    trajectory: JointTrajectory,
    limits: JointLimits,
    rate: float = DEFAULT_RATE_HZ,
    subdivisions: int = DEFAULT_SUBDIVISIONS,
) -> ExportPlan:
    """Retime ``trajectory`` within ``limits`` (:func:`toolimit.deploy.retime.retime`) and sample it at ``rate`` Hz.

    Raises :class:`PathOutsideLimits` for a sample outside the position limits, ValueError for
    mismatched joints or a bad rate.
    """
    if tuple(trajectory.joint_names) != limits.joint_names:
        raise InputError(
            f"trajectory joints {list(trajectory.joint_names)} do not match "
            f"{limits.robot}'s joints {list(limits.joint_names)}"
        )
    if not (math.isfinite(rate) and rate > 0):
        raise InputError(f"rate must be a positive number of Hz, got {rate}")
    path = retime(trajectory.q, trajectory.dt, limits, subdivisions)
    samples = path.sample(rate)
    checks = check_samples(limits, samples.times, samples.as_dict())
    failed = [check.describe() for check in checks if not check.passed]
    if failed:  # the retiming guarantees the limits: this is a bug, not bad input
        raise RuntimeError(f"retimed trajectory breaks a limit: {'; '.join(failed)}")
    return ExportPlan(trajectory, limits, rate, path, samples, checks)


def _csv(times: np.ndarray, positions: np.ndarray, joint_names: tuple[str, ...]) -> str:
    buffer = io.StringIO()
    np.savetxt(
        buffer,
        np.column_stack([times, positions]),
        delimiter=",",
        fmt="%.12f",
        header=",".join(("time_s",) + tuple(joint_names)),
        comments="",
    )
    return buffer.getvalue()


def export_trajectory(
    trajectory: JointTrajectory,
    robot: str,
    out_dir: str | Path,
    rate: float = DEFAULT_RATE_HZ,
    subdivisions: int = DEFAULT_SUBDIVISIONS,
    source: str | None = None,
) -> ExportPlan:
    """Retime ``trajectory`` within ``robot``'s published limits and write the CSV and JSON to ``out_dir``.

    Raises :class:`PathOutsideLimits` (nothing written) if a path sample is outside a position
    limit, ValueError for an unsupported robot or mismatched joints.
    """
    plan = plan_export(trajectory, published_limits(robot), rate, subdivisions)
    summary = {
        "robot": robot,
        "joint_names": list(trajectory.joint_names),
        "rate_hz": rate,
        "duration_s": plan.path.duration,
        "optimised_duration_s": plan.optimised_duration,
        "n_samples": len(plan.samples.times),
        "path_deviation_rad": plan.path.path_deviation,
        "subdivisions": subdivisions,
        "units": {"time": "s", **UNITS},
        "retiming": METHOD,
        "limits": plan.limits.as_dict(),
        "checks": {check.quantity: check.as_dict() for check in plan.checks},
        "base": {
            "x_m": float(trajectory.base[0]),
            "y_m": float(trajectory.base[1]),
            "yaw_rad": float(trajectory.base[2]),
            "frame": "world; place the robot base here before execution",
        },
        "files": {"csv": TRAJECTORY_CSV},
        "source": source,
    }
    documents = {
        TRAJECTORY_CSV: _csv(plan.samples.times, plan.samples.position, trajectory.joint_names),
        SUMMARY_JSON: json.dumps(summary, indent=2) + "\n",
    }
    out_dir = Path(out_dir)
    with contextlib.ExitStack() as stack:  # every file is complete before the first is renamed into place
        for name, text in documents.items():
            stack.enter_context(atomic_path(out_dir / name)).write_text(text)
    return plan
