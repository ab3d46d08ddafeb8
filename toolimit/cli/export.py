"""``toolimit export``: a joint trajectory retimed within a real robot's limits, for streaming (CSV + JSON).

    toolimit export --trajectory DIR --robot panda --out DIR [--rate 1000] [--subdivisions 4]

Reads DIR/trajectory.npz, retimes its joint path within the robot's published velocity,
acceleration and jerk limits (slower only where a limit requires it, never past a position limit),
samples it at --rate Hz and writes OUT/joint_trajectory.csv and OUT/joint_trajectory.json. A path
sample outside a position limit, which no retiming can fix, is refused in one line naming the
joint, sample and value, and nothing is written.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from toolimit.cli import check_writable_folder
from toolimit.cli.flags import Flag, add_flags, apply_flags
from toolimit.deploy import (
    SUPPORTED_ROBOTS,
    export_trajectory,
    load_trajectory,
    published_limits,
)
from toolimit.deploy.export import SUMMARY_JSON, TRAJECTORY_CSV
from toolimit.pipeline.settings import ExportSettings
from toolimit.trajopt.result import TRAJECTORY_NPZ

#: Every flag of ``toolimit export`` built from its settings.
EXPORT_FLAGS = (Flag("rate"), Flag("subdivisions"))


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
    add_flags(parser, EXPORT_FLAGS, {"": ExportSettings()})
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    settings = apply_flags(ExportSettings(), EXPORT_FLAGS, args)
    published_limits(args.robot)  # an unsupported robot is refused before anything is read
    check_writable_folder(args.out, "--out")
    trajectory = load_trajectory(args.trajectory)
    plan = export_trajectory(
        trajectory,
        args.robot,
        args.out,
        rate=settings.rate,
        subdivisions=settings.subdivisions,
        source=str(args.trajectory / TRAJECTORY_NPZ),
    )
    ratios = ", ".join(f"{check.quantity} {check.ratio:.2f}" for check in plan.checks if check.quantity != "position")
    duration, optimised = plan.path.duration, plan.optimised_duration
    print(
        f"retimed within {args.robot}'s limits: {duration:.3f} s against {optimised:.3f} s optimised "
        f"({duration / optimised:.2f}x); the path stays within {plan.path.path_deviation:.4f} rad of every "
        f"optimised sample"
    )
    print(f"peak |value| / limit: {ratios}; every position inside its limits")
    print(
        f"wrote {args.out / TRAJECTORY_CSV} ({len(plan.samples.times)} samples at {settings.rate:g} Hz) "
        f"and {args.out / SUMMARY_JSON}"
    )
    return 0
