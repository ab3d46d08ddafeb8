"""``toolimit trajopt``: optimise a robot's base and joint trajectory to follow a tool motion.

The command line of :func:`toolimit.pipeline.trajopt_stage` (from an alignment folder: every
candidate tracked and replayed, the best kept, ``OUT/selection.json``) and
:func:`toolimit.pipeline.trajopt_from_poses` (a poses file: ``tip_position`` (T, 3),
``tip_quaternion_wxyz`` (T, 4), ``fps``; toolimit's tool-frame convention); the flags are the
fields of :class:`toolimit.pipeline.TrajoptSettings`, with the same defaults as ``toolimit run``, and
``--action-limit``, the learner's (``toolimit learn``), for the learning tasks the shortlist tracks in.
Output: ``OUT/trajectory.npz`` and ``OUT/trajectory.json`` (see :mod:`toolimit.trajopt.result`).
Exit codes: 0 done, 1 no candidate's robot replay earned a reward, 2 bad input (nothing written).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from toolimit.cli import (
    CliError,
    add_frame_argument,
    add_out_argument,
    add_tool_argument,
    check_choice,
    check_output_file,
    check_output_folder,
    load_poses,
)
from toolimit.cli.flags import Flag, add_flags, apply_flags, show_workers
from toolimit.cli.learn import LEARNING_FLAGS
from toolimit.learn.training import LearningConfig
from toolimit.pipeline.settings import INIT_CHOICES, TrajoptSettings


def parse_time_scales(text: str) -> tuple[float, ...]:
    """The scales of --time-scale: 'auto' is ``TIME_SCALE_GRID``, else comma-separated positive numbers
    (argparse turns the error into one line naming the flag)."""
    from toolimit.trajopt import TIME_SCALE_GRID

    if text == "auto":
        return TIME_SCALE_GRID
    try:
        values = tuple(float(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected positive numbers (comma-separated) or 'auto', got {text!r}"
        ) from None
    if not all(0 < value < float("inf") for value in values):
        raise argparse.ArgumentTypeError(f"every scale must be a positive finite number, got {text!r}")
    return values


def _show_scales(scales: tuple[float, ...]) -> str:
    return ",".join(f"{scale:g}" for scale in scales)


#: Every flag of ``toolimit trajopt`` built from its settings (:class:`TrajoptSettings`).
TRAJOPT_FLAGS = (
    Flag("weights.velocity", "--velocity-weight"),
    Flag("weights.posture", "--posture-weight"),
    Flag("starts"),
    Flag("init", choices=tuple(INIT_CHOICES)),
    Flag("time_scales", "--time-scale", parse=parse_time_scales, show=_show_scales),
    Flag("select_by_robot"),
    Flag("shortlist"),
    Flag("shortlist_episodes"),
    Flag("seed"),
    Flag("workers", show=show_workers),
)
#: The learner's action limit (a field of :class:`~toolimit.learn.training.LearningConfig`): the
#: shortlist tracks its candidates in the learning task the learner will build, with its span.
SHORTLIST_SPAN_FLAGS = tuple(flag for flag in LEARNING_FLAGS if flag.path == "action_limit")


def register(subparsers: argparse._SubParsersAction) -> None:
    from toolimit.robots import ROBOTS

    parser = subparsers.add_parser(
        "trajopt",
        help="optimise a robot trajectory tracking the aligned tool motion (stage iii)",
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("--robot", required=True, help=f"robot model ({', '.join(ROBOTS)})")
    add_tool_argument(parser)
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--alignment", type=Path, help="alignment output folder (reads candidates.npz)")
    source.add_argument("--poses", type=Path, help=".npz with tip_position, tip_quaternion_wxyz, fps")
    add_frame_argument(parser)
    add_out_argument(parser)
    add_flags(parser, TRAJOPT_FLAGS, {"": TrajoptSettings()})
    add_flags(parser, SHORTLIST_SPAN_FLAGS, {"": LearningConfig()})
    parser.add_argument("--rerun", type=Path, default=None, help="also save a rerun recording (.rrd) here")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from toolimit.deploy import SUPPORTED_ROBOTS
    from toolimit.pipeline.stages import describe_trajectory, trajopt_from_poses, trajopt_stage
    from toolimit.robots import ROBOTS, make_robot
    from toolimit.tools import TOOLS
    from toolimit.trajopt.result import TRAJECTORY_JSON, TRAJECTORY_NPZ, UpsideDownTracking

    check_choice("--robot", args.robot, ROBOTS, "robot")
    check_choice("--tool", args.tool, sorted(TOOLS), "tool")
    settings = apply_flags(TrajoptSettings(), TRAJOPT_FLAGS, args)
    action_limit = apply_flags(LearningConfig(), SHORTLIST_SPAN_FLAGS, args).action_limit
    if action_limit is not None and args.poses is not None:
        raise CliError("--action-limit: only with --alignment (the span of the shortlist's tracking)")
    check_output_folder(args.out, "--out")
    check_output_file(args.rerun, "--rerun", ".rrd")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UpsideDownTracking)
        if args.alignment is not None:
            if not args.alignment.is_dir():
                raise CliError(f"--alignment: no such folder: {args.alignment}")
            stage = trajopt_stage(
                args.alignment, args.robot, args.out, settings, not args.quiet, args.tool, action_limit=action_limit
            )
            result = stage.trajectory
            targets = stage.candidates[stage.trajectory.scene.candidate].targets if stage.trajectory.scene else None
            for line in describe_trajectory(stage):
                print(line)
        else:
            targets = load_poses(args.poses, args.frame)
            result = trajopt_from_poses(
                targets, args.robot, args.tool, args.out, settings=settings, progress=not args.quiet
            )
            print(f"{args.robot}: {result.describe()}")
    for warning in caught:
        print(f"note: {warning.message}", file=sys.stderr)
    if args.rerun is not None:
        from toolimit.viz.rerun_trajopt import save_trajectory_recording

        positions = None if targets is None else targets.positions
        save_trajectory_recording(result, make_robot(args.robot, tool=args.tool), args.rerun, positions)
    written = f"wrote {args.out / TRAJECTORY_NPZ} and {args.out / TRAJECTORY_JSON}"
    if args.robot not in SUPPORTED_ROBOTS:
        written += f" (export to a real robot needs published limits: {', '.join(SUPPORTED_ROBOTS)})"
    print(written)
    return 0
