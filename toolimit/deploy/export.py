"""Export a joint trajectory for open-loop execution on a real robot.

Input: ``DIR/trajectory.npz`` written by trajectory optimisation or by a policy's rollout: ``q``
(T+1, N) rad, ``v`` (T, N) rad/s with ``q[t] = q[t-1] + dt v[t-1]``, ``base`` (3,) = (x m, y m,
yaw rad) world placement of the robot base, ``joint_names`` (N,), ``dt`` (s).

The joint path q is retimed within the robot's published position, velocity, acceleration and jerk
limits narrowed by :class:`~toolimit.robots.limits.Margins` (by default 0.01 rad inside every
position limit and 0.95 of the others: Franka aborts a motion that reaches a limit, which it states
as a strict inequality), slowed down only where a limit requires it
(:mod:`toolimit.deploy.retime`), and sampled at ``rate`` Hz. A path sample outside the narrowed
position limits is refused; a path that departs from its samples by more than
:data:`DEVIATION_TOLERANCE_RAD` gets a :class:`PathDeviation` warning. A policy learnt within the
same margins (:mod:`toolimit.robots.motion_bound`) exports at its own timing. Given the learning
task, the export is replayed open-loop in its scene (:mod:`toolimit.deploy.open_loop`) and the
outcome recorded.

Output (each file written atomically, both complete before either is renamed into place):

* ``joint_trajectory.csv``: the commands to stream to the robot, every 1/rate s from rest to rest;
  header ``time_s`` then the joint names, positions in rad;
* ``joint_trajectory.json``: joint names, rate, units, exported and optimised durations (and the
  braking that brings a path ending in motion to rest), the largest
  gap between the exported path and the optimised samples, the limits and margins used, every
  quantity's worst sample, the retiming method, the base placement, and the open-loop replay's
  outcome when it ran.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from toolimit.artifacts import atomic_path
from toolimit.deploy.open_loop import OPEN_LOOP_EPISODES, OpenLoopResult, replay_open_loop
from toolimit.deploy.retime import METHOD, RetimedPath, SampledTrajectory, retime
from toolimit.errors import InputError
from toolimit.learn.task import LearningTask
from toolimit.robots.limits import UNITS, JointLimits, Margins, QuantityCheck, check_samples, published_limits
from toolimit.trajopt.result import JointTrajectory

TRAJECTORY_CSV = "joint_trajectory.csv"
SUMMARY_JSON = "joint_trajectory.json"
DEFAULT_RATE_HZ = 1000.0
#: Command rates an export takes, Hz: the Panda takes commands at 1 kHz; below 10 Hz the samples
#: cannot follow a motion learnt at 24 Hz, above 10 kHz no arm takes them.
RATE_RANGE_HZ = (10.0, 10_000.0)
#: The fewest samples an export streams: fewer is no trajectory.
MIN_SAMPLES = 10
#: The largest gap between the exported path and the trajectory's samples without a warning, rad.
DEVIATION_TOLERANCE_RAD = 0.02


class PathDeviation(UserWarning):
    """The exported path departs from the trajectory's samples by more than the tolerance."""


@dataclass(frozen=True)
class ExportPlan:
    """The retimed trajectory: the samples to stream and each quantity's worst sample against its limit."""

    trajectory: JointTrajectory
    limits: JointLimits
    rate: float
    path: RetimedPath
    samples: SampledTrajectory
    checks: list[QuantityCheck]
    open_loop: OpenLoopResult | None = None

    @property
    def optimised_duration(self) -> float:
        """Duration of the optimised trajectory, s (T dt)."""
        return self.trajectory.dt * (len(self.trajectory.q) - 1)


def plan_export(
    trajectory: JointTrajectory,
    limits: JointLimits,
    rate: float = DEFAULT_RATE_HZ,
    subdivisions: int | None = None,
) -> ExportPlan:
    """Retime ``trajectory`` within ``limits`` (:func:`toolimit.deploy.retime.retime`) and sample it at ``rate`` Hz.

    Raises :class:`PathOutsideLimits` for a sample outside the position limits, InputError for
    mismatched joints, a rate outside :data:`RATE_RANGE_HZ` or fewer than :data:`MIN_SAMPLES`
    samples; warns :class:`PathDeviation` for a path farther than the tolerance from its samples.
    """
    if tuple(trajectory.joint_names) != limits.joint_names:
        raise InputError(
            f"trajectory joints {list(trajectory.joint_names)} do not match "
            f"{limits.robot}'s joints {list(limits.joint_names)}"
        )
    low, high = RATE_RANGE_HZ
    if not (math.isfinite(rate) and low <= rate <= high):
        raise InputError(f"rate must be between {low:g} and {high:g} Hz, got {rate:g}")
    path = retime(trajectory.q, trajectory.dt, limits, subdivisions)
    if path.duration * rate + 1 < MIN_SAMPLES:
        raise InputError(
            f"a {path.duration:.3g} s trajectory at {rate:g} Hz gives fewer than {MIN_SAMPLES} samples: "
            f"raise the rate or export a longer trajectory"
        )
    if path.path_deviation > DEVIATION_TOLERANCE_RAD:
        warnings.warn(
            f"the exported path departs from the trajectory's samples by up to {path.path_deviation:.3f} rad "
            f"(tolerance {DEVIATION_TOLERANCE_RAD} rad): the robot will not follow the optimised path closely; "
            f"more subdivisions keep closer to it",
            PathDeviation,
            stacklevel=2,
        )
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
    subdivisions: int | None = None,
    margins: Margins = Margins(),
    source: str | None = None,
    check: LearningTask | None = None,
    check_episodes: int = OPEN_LOOP_EPISODES,
) -> ExportPlan:
    """Retime ``trajectory`` within ``robot``'s published limits narrowed by ``margins`` and write
    the CSV and JSON to ``out_dir``; with ``check``, the learning task the trajectory was learnt
    in, replay the export open-loop in its scene for ``check_episodes`` episodes first and record
    the outcome.

    Raises :class:`PathOutsideLimits` (nothing written) if a path sample is outside a narrowed
    position limit, InputError for an unsupported robot, mismatched joints or a bad rate.
    """
    plan = plan_export(trajectory, published_limits(robot).within(margins), rate, subdivisions)
    if check is not None:
        if check.robot != robot or tuple(check.joint_names) != tuple(trajectory.joint_names):
            raise InputError(
                f"the check's task is for the {check.robot}'s joints {list(check.joint_names)}, not this trajectory's"
            )
        result = replay_open_loop(plan.samples.times, plan.samples.position, check, check_episodes)
        plan = dataclasses.replace(plan, open_loop=result)
    summary = {
        "robot": robot,
        "joint_names": list(trajectory.joint_names),
        "rate_hz": rate,
        "duration_s": plan.path.duration,
        "optimised_duration_s": plan.optimised_duration,
        "braking_s": plan.path.braking_steps * plan.trajectory.dt,
        "n_samples": len(plan.samples.times),
        "path_deviation_rad": plan.path.path_deviation,
        "subdivisions": plan.path.subdivisions,
        "units": {"time": "s", **UNITS},
        "retiming": METHOD,
        "margins": margins.as_dict(),
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
        "open_loop": None if plan.open_loop is None else plan.open_loop.record(),
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
