"""``toolimit export``: a limit-checked joint trajectory for a real robot (CSV + JSON).

    toolimit export --trajectory DIR --robot panda --out DIR [--rate 1000] [--time-scale 1.0]

Reads DIR/trajectory.npz, interpolates it smoothly, resamples it at --rate Hz and checks position,
velocity, acceleration and jerk against the robot's published limits. On any violation it prints
one line naming the joint, quantity, time and value (and the smallest time scale that would pass)
and writes nothing.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from toolimit.deploy import SUPPORTED_ROBOTS, export_trajectory, load_trajectory
from toolimit.deploy.export import CONTROL_CSV, DEFAULT_RATE_HZ, RESAMPLED_CSV, SUMMARY_JSON


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "export",
        help="write a limit-checked joint trajectory (CSV + JSON) for open-loop execution on a real robot",
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("--trajectory", required=True, type=Path, metavar="DIR",
                        help="folder holding trajectory.npz (from `toolimit trajopt`)")
    parser.add_argument("--robot", required=True,
                        help=f"robot whose published limits apply ({', '.join(SUPPORTED_ROBOTS)})")
    parser.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder")
    parser.add_argument("--rate", type=float, default=DEFAULT_RATE_HZ, help="resampling rate in Hz (default 1000)")
    parser.add_argument("--time-scale", type=float, default=1.0,
                        help="stretch the trajectory's own time by this factor (> 1 is slower; default 1)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    trajectory = load_trajectory(args.trajectory)
    plan = export_trajectory(trajectory, args.robot, args.out, rate=args.rate, time_scale=args.time_scale,
                             source=str(args.trajectory / "trajectory.npz"))
    ratios = ", ".join(f"{check.quantity} {check.ratio:.2f}" for check in plan.checks if check.quantity != "position")
    duration = plan.samples.times[-1]
    print(f"wrote {args.out / CONTROL_CSV}, {args.out / RESAMPLED_CSV} ({len(plan.samples.times)} samples at "
          f"{args.rate:g} Hz, {duration:.3f} s) and {args.out / SUMMARY_JSON}")
    print(f"all limits respected (peak |value| / limit: {ratios})")
    return 0
