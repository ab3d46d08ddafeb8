"""``toolimit trajopt``: optimise a robot's base and joint trajectory to follow a tool motion.

Input: an alignment folder (``DIR/aligned_demo.npz``) or a poses file (``tip_position`` (T, 3),
``tip_quaternion_wxyz`` (T, 4), ``fps``; toolimit's tool-frame convention). Output:
``OUT/trajectory.npz`` and ``OUT/trajectory.json`` (see :mod:`toolimit.trajopt.result`).
Exit codes: 0 done, 2 bad input (nothing written).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from toolimit.cli import (
    CliError,
    add_frame_argument,
    add_out_argument,
    add_seed_argument,
    add_tool_argument,
    add_workers_argument,
    check_choice,
    check_count,
    check_output_file,
    check_output_folder,
    load_poses,
    worker_count,
)


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
    source.add_argument("--alignment", type=Path, help="alignment output folder (reads aligned_demo.npz)")
    source.add_argument("--poses", type=Path, help=".npz with tip_position, tip_quaternion_wxyz, fps")
    add_frame_argument(parser)
    add_out_argument(parser)
    parser.add_argument(
        "--time-scale",
        default="1",
        help="slow-down factor (>0; default: 1), or several comma-separated, or 'auto' (1,1.5,2,2.5,3,4,5): of "
        "several, the smallest whose tracking error has a median under 1 cm, or with --select-by-robot the "
        "one whose robot replay earns the most",
    )
    parser.add_argument("--starts", type=int, default=8, help="base initialisations (default: 8)")
    add_seed_argument(parser, "seed of the random starts beyond 8")
    add_workers_argument(parser)
    parser.add_argument(
        "--init",
        choices=("hold", "rollout", "both"),
        default="both",
        help="joint initialisation of every start: the rest pose held, a differential-IK rollout along the "
        "targets, or both (default: both; the better result is kept)",
    )
    parser.add_argument(
        "--velocity-weight",
        type=float,
        default=0.01,
        help="w_v, weight of the joint velocities (rad/s)^2 against the pose error (default: 0.01)",
    )
    parser.add_argument(
        "--posture-weight",
        type=float,
        default=0.0,
        help="w_p, weight of the joints' distance to the rest posture (rad)^2 (default: 0, off)",
    )
    parser.add_argument(
        "--select-by-robot",
        action="store_true",
        help="with --alignment: track every alignment candidate (candidates.npz), replay the robot in each "
        "candidate's scene and keep the one whose robot replay earns the most goal reward (the paper's "
        "selection); also writes OUT/selection.json",
    )
    parser.add_argument("--rerun", type=Path, default=None, help="also save a rerun recording (.rrd) here")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def parse_time_scales(text: str) -> tuple[float, ...]:
    """The scales of --time-scale: 'auto' is ``TIME_SCALE_GRID``, else comma-separated positive numbers."""
    from toolimit.trajopt import TIME_SCALE_GRID

    if text == "auto":
        return TIME_SCALE_GRID
    try:
        values = tuple(float(part) for part in text.split(","))
    except ValueError:
        raise CliError(f"--time-scale: expected positive numbers (comma-separated) or 'auto', got {text!r}") from None
    if not all(0 < value < float("inf") for value in values):
        raise CliError(f"--time-scale: every scale must be a positive finite number, got {text!r}")
    return values


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from toolimit.align.outputs import ALIGNED_DEMO_NPZ
    from toolimit.deploy import SUPPORTED_ROBOTS
    from toolimit.robots import ROBOTS, make_robot
    from toolimit.tools import TOOLS
    from toolimit.trajopt import (
        TrackingWeights,
        TrackOptions,
        choose_time_scale,
        track,
    )
    from toolimit.trajopt.result import TRAJECTORY_JSON, TRAJECTORY_NPZ

    check_choice("--robot", args.robot, ROBOTS, "robot")
    check_choice("--tool", args.tool, sorted(TOOLS), "tool")
    check_count("--starts", args.starts)
    worker_count(args.workers)  # checked before any work
    check_count("--seed", args.seed, minimum=0)
    scales = parse_time_scales(args.time_scale)
    for flag, value in (("--velocity-weight", args.velocity_weight), ("--posture-weight", args.posture_weight)):
        if not (value >= 0 and value < float("inf")):
            raise CliError(f"{flag}: must be a finite number >= 0, got {value}")
    check_output_folder(args.out, "--out")
    check_output_file(args.rerun, "--rerun", ".rrd")
    if args.select_by_robot and args.alignment is None:
        raise CliError("--select-by-robot: needs --alignment DIR (the candidates of an alignment)")
    if args.alignment is not None:
        if not args.alignment.is_dir():
            raise CliError(f"--alignment: no such folder: {args.alignment}")
        poses_path = args.alignment / ALIGNED_DEMO_NPZ
        if not poses_path.is_file():
            raise CliError(f"--alignment: {poses_path} not found (run `toolimit align` first)")
    else:
        poses_path = args.poses
    targets = load_poses(poses_path, args.frame)

    robot = make_robot(args.robot, tool=args.tool)
    rng = np.random.default_rng(args.seed)
    initialisations = ("hold", "rollout") if args.init == "both" else (args.init,)
    options = TrackOptions(
        weights=TrackingWeights(velocity=args.velocity_weight, posture=args.posture_weight),
        starts=args.starts,
        time_scale=scales[0],
        initialisations=initialisations,
        progress=not args.quiet,
    )
    if args.select_by_robot:
        targets, result = _select_by_robot(args, robot, options, scales)
        if result is None:
            return 1
    elif len(scales) > 1:
        result = choose_time_scale(robot, targets, options, grid=scales, rng=rng)
    else:
        result = track(robot, targets, options, rng=rng)
    result.save(args.out)
    if args.rerun is not None:
        from toolimit.viz.rerun_trajopt import save_trajectory_recording

        save_trajectory_recording(result, robot, args.rerun, targets.positions)
    print(f"{args.robot}: {result.describe()}")
    if result.upside_down:
        print(
            f"note: the {args.tool} is tracked upside down (median rotation error "
            f"{np.degrees(np.median(result.rotation_error)):.0f} deg): its position follows the targets, its "
            "orientation does not (trajectory.json has the error at every step)",
            file=sys.stderr,
        )
    written = f"wrote {args.out / TRAJECTORY_NPZ} and {args.out / TRAJECTORY_JSON}"
    if args.robot in SUPPORTED_ROBOTS:
        print(f"{written}; next: toolimit export --trajectory {args.out} --robot {args.robot} --out {args.out}_export")
    else:
        print(f"{written} (export to a real robot needs published limits: {', '.join(SUPPORTED_ROBOTS)})")
    return 0


def _select_by_robot(args: argparse.Namespace, robot, options, time_scales: tuple[float, ...]):
    """Track and replay every candidate of ``args.alignment`` at each of ``time_scales``; (targets,
    result) of the best, or (None, None) after saying why no candidate's robot replay earned a reward."""
    from toolimit.align.outputs import CANDIDATES_NPZ
    from toolimit.artifacts import save_json
    from toolimit.trajopt.selection import SELECTION_JSON, load_candidates, select_by_robot_execution

    tool, world, candidates = load_candidates(args.alignment / CANDIDATES_NPZ)
    if tool != args.tool:
        raise CliError(f"--tool: the alignment in {args.alignment} is for the {tool}, not the {args.tool}")
    selection = select_by_robot_execution(
        robot,
        candidates,
        tool,
        world,
        options,
        seed=args.seed,
        progress=not args.quiet,
        time_scales=time_scales,
        workers=worker_count(args.workers),
    )
    save_json(args.out / SELECTION_JSON, selection.record(candidates))
    for k, (trajectory, reward) in enumerate(zip(selection.trajectories, selection.robot_rewards)):
        if trajectory is None:
            print(f"candidate {k}: refused ({selection.refusals[k]})")
        else:
            print(f"candidate {k}: robot replay reward {reward:.1f}; {trajectory.describe()}")
    if selection.best is None:
        print(f"no candidate's robot replay earned a goal reward; wrote {args.out / SELECTION_JSON}", file=sys.stderr)
        return None, None
    print(
        f"selected candidate {selection.best} (alignment reward "
        f"{candidates[selection.best].alignment_reward:.1f}, robot reward {selection.robot_rewards[selection.best]:.1f})"
    )
    return candidates[selection.best].targets, selection.trajectories[selection.best]
