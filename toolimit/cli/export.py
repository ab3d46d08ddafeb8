"""``toolimit export``: a joint trajectory retimed within a real robot's limits, for streaming (CSV + JSON).

    toolimit export --trajectory DIR --robot panda --out DIR [--rate 1000] [--check TASK]

Reads DIR/trajectory.npz, retimes its joint path within the robot's published velocity,
acceleration and jerk limits narrowed by the margins (slower only where a limit requires it, never
past a position limit), samples it at --rate Hz and writes OUT/joint_trajectory.csv and
OUT/joint_trajectory.json. With --check, the learning task the trajectory runs in (a task.npz or
the folder of a learnt policy), the export is first replayed open-loop in its scene and the
success recorded. A path sample outside a position limit, which no retiming can fix, is refused
in one line naming the joint, sample and value, and nothing is written.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from toolimit.cli import check_writable_folder
from toolimit.cli.flags import Flag, add_flags, apply_flags
from toolimit.deploy import (
    SUPPORTED_ROBOTS,
    export_trajectory,
    load_trajectory,
    published_limits,
)
from toolimit.deploy.export import SUMMARY_JSON, TRAJECTORY_CSV, PathDeviation
from toolimit.learn.task import LearningTask
from toolimit.pipeline.settings import ExportSettings
from toolimit.trajopt.result import TRAJECTORY_NPZ

#: Every flag of ``toolimit export`` built from its settings.
EXPORT_FLAGS = (
    Flag("rate"),
    Flag("subdivisions", show=lambda value: "auto" if value is None else str(value)),
    Flag("position_margin"),
    Flag("velocity_scale"),
    Flag("acceleration_scale"),
    Flag("jerk_scale"),
    Flag("check_episodes"),
)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "export",
        help="retime a joint trajectory within a real robot's limits and write it (CSV + JSON) for open-loop execution",
        description=__doc__.splitlines()[0],
    )
    parser.add_argument(
        "--trajectory",
        required=True,
        type=Path,
        metavar="DIR",
        help="folder holding trajectory.npz (from `toolimit trajopt`)",
    )
    parser.add_argument(
        "--robot", required=True, help=f"robot whose published limits apply ({', '.join(SUPPORTED_ROBOTS)})"
    )
    parser.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder")
    parser.add_argument(
        "--check",
        type=Path,
        metavar="TASK",
        help="replay the export open-loop in this learning task's scene first (task.npz, or a policy's folder)",
    )
    add_flags(parser, EXPORT_FLAGS, {"": ExportSettings()})
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    settings = apply_flags(ExportSettings(), EXPORT_FLAGS, args)
    published_limits(args.robot)  # an unsupported robot is refused before anything is read
    check_writable_folder(args.out, "--out")
    trajectory = load_trajectory(args.trajectory)
    task = None if args.check is None else LearningTask.load(args.check)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PathDeviation)
        plan = export_trajectory(
            trajectory,
            args.robot,
            args.out,
            rate=settings.rate,
            subdivisions=settings.subdivisions,
            margins=settings.margins,
            source=str(args.trajectory / TRAJECTORY_NPZ),
            check=task,
            check_episodes=settings.check_episodes,
        )
    for warning in caught:
        print(f"warning: {warning.message}", file=sys.stderr)
    ratios = ", ".join(f"{check.quantity} {check.ratio:.2f}" for check in plan.checks if check.quantity != "position")
    duration, optimised = plan.path.duration, plan.optimised_duration
    print(
        f"retimed within {args.robot}'s limits ({settings.margins.describe()}): {duration:.3f} s against "
        f"{optimised:.3f} s optimised ({duration / optimised:.2f}x); the path stays within "
        f"{plan.path.path_deviation:.4f} rad of every optimised sample"
    )
    print(f"peak |value| / narrowed limit: {ratios}; every position inside the narrowed limits")
    if plan.open_loop is not None:
        record = plan.open_loop.record()
        print(
            f"open-loop replay in {args.check}: success {record['success_rate']:.2f} over {record['episodes']} "
            f"episodes, goal reward {record['goal_reward_mean']:.2f}"
        )
    print(
        f"wrote {args.out / TRAJECTORY_CSV} ({len(plan.samples.times)} samples at {settings.rate:g} Hz) "
        f"and {args.out / SUMMARY_JSON}"
    )
    return 0
