"""``toolimit align``: find scene parameters under which a demonstration reaches the goal.

Writes ``DIR/alignment.json`` (the search's record) and ``DIR/aligned_demo.npz`` (the best
candidate's aligned motion); optionally a rerun recording (``--rerun``) and, in the 3d world, the
best candidate's replay as a self-contained HTML page (``--html``). An interrupted search (SIGINT,
e.g. Ctrl-C: exit code 130; SIGTERM: 143) saves ``DIR/alignment_checkpoint.json`` if any sample
finished; the same command then resumes it. Exit codes: 0 found, 1 no candidate within the budget (the record
is still written, with an empty candidate list, and no aligned demo), 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from toolimit.cli import (
    CliError,
    add_out_argument,
    add_scene_arguments,
    add_seed_argument,
    add_workers_argument,
    check_count,
    check_output_file,
    check_output_folder,
    check_scene,
    check_writable_folder,
    worker_count,
)

DEFAULT_SAMPLES = 20_000
#: The search's progress in the output folder while it runs (removed when it ends).
CHECKPOINT_JSON = "alignment_checkpoint.json"
DEFAULT_CANDIDATES = 5


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "align",
        help="align a scene to a demonstration (stage ii)",
        description="Find scene parameters under which a demonstration reaches the goal (stage ii): "
        "writes OUT/alignment.json and OUT/aligned_demo.npz. Exit code 1 when no candidate is found.",
    )
    add_scene_arguments(parser, "planar")
    parser.add_argument(
        "--demo",
        required=True,
        type=Path,
        help="demonstration file (project .npz, real aligned .npz or estimator .pkl)",
    )
    parser.add_argument("--samples", type=int, default=DEFAULT_SAMPLES, help="sample budget (default: 20000)")
    parser.add_argument(
        "--candidates",
        type=int,
        default=DEFAULT_CANDIDATES,
        help=f"stop after this many samples with a reward (default: {DEFAULT_CANDIDATES})",
    )
    add_seed_argument(parser)
    add_workers_argument(parser)
    add_out_argument(parser)
    parser.add_argument("--rerun", type=Path, default=None, help="also save a rerun recording (.rrd) here")
    parser.add_argument(
        "--html",
        type=Path,
        default=None,
        help="3d world only: also save the best candidate's replay as a self-contained meshcat page (.html)",
    )
    parser.add_argument(
        "--z-offset-std",
        type=float,
        default=None,
        help="spread of the sampled vertical offset p_z, m (default 0.1; the paper's 0.5 suits recordings "
        "whose heights are not measured from the ground)",
    )
    parser.add_argument("--no-clean", action="store_true", help="use the demo as loaded, without cleaning")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def _check_arguments(args: argparse.Namespace) -> int:
    """Validate before any work; returns the worker count."""
    check_scene(args.tool, args.world)
    check_count("--samples", args.samples)
    check_count("--candidates", args.candidates)
    if args.z_offset_std is not None and not args.z_offset_std > 0:
        raise CliError(f"--z-offset-std: must be a positive number of metres, got {args.z_offset_std}")
    check_count("--seed", args.seed, minimum=0)
    workers = worker_count(args.workers)
    if not args.demo.is_file():
        raise CliError(f"--demo: no such file: {args.demo}")
    check_output_folder(args.out, "--out")
    check_output_file(args.rerun, "--rerun", ".rrd")
    if args.html is not None:
        if args.html.suffix != ".html":
            raise CliError(f"--html: expected a .html file name, got {args.html}")
        if args.world != "3d":
            raise CliError(f"--html: the meshcat replay draws the 3d worlds, not the {args.world} world")
        check_writable_folder(args.html.parent, "--html")
    return workers


def run(args: argparse.Namespace) -> int:
    from toolimit.align.config import AlignmentConfig
    from toolimit.align.outputs import (
        ALIGNED_DEMO_NPZ,
        ALIGNMENT_JSON,
        CANDIDATES_NPZ,
        write_alignment,
    )
    from toolimit.align.search import SearchInterrupted, align
    from toolimit.demos import load_demo
    from toolimit.tools import tool_record

    workers = _check_arguments(args)
    demo = load_demo(args.demo, tool=args.tool)  # also names the tool of files that do not store it
    settings = {} if args.z_offset_std is None else {"z_offset_std": args.z_offset_std}
    config = AlignmentConfig(samples=args.samples, candidates=args.candidates, **settings)
    checkpoint = args.out / CHECKPOINT_JSON
    if checkpoint.is_file():
        print(f"found {checkpoint}: the search resumes from it if it was made with the same settings")
    try:
        result = align(
            demo,
            args.tool,
            args.world,
            config,
            seed=args.seed,
            workers=workers,
            progress=not args.quiet,
            checkpoint=checkpoint,
            clean=not args.no_clean,
        )
    except SearchInterrupted as stop:
        found = f"{stop.samples_tried} samples examined, {stop.candidates} candidate(s)"
        if stop.checkpoint is not None:
            print(
                f"interrupted ({stop.signal_name}) after {found}: progress saved to {stop.checkpoint}; "
                "run the same command again to resume",
                file=sys.stderr,
            )
        else:
            print(f"interrupted ({stop.signal_name}) before any sample finished: nothing was saved", file=sys.stderr)
        return stop.exit_code
    write_alignment(result, args.out, str(args.demo), cleaned=not args.no_clean, workers=workers)
    if result.cleaning is not None:
        print(
            f"cleaned demo: {len(result.cleaning.replaced_frames)} of {demo.n_frames} frames replaced "
            f"({len(result.cleaning.head_replaced_frames)} of them with the head's position)"
        )
    rejected = result.samples_rejected / max(result.samples_tried, 1)
    print(
        f"{len(result.candidates)} candidate(s) in {result.samples_tried} samples "
        f"({rejected:.0%} rejected), {result.wall_time_s:.1f} s with {workers} worker(s)"
    )
    if args.rerun is not None:
        from toolimit.viz.rerun_alignment import save_alignment_recording

        written = save_alignment_recording(result, args.rerun)
        print(f"rerun recording: {args.rerun}" if written else "rerun recording skipped (RERUN=off)")
    best = result.best
    if args.html is not None and best is not None:
        from toolimit.viz.meshcat_alignment import save_alignment_html

        print(f"meshcat replay of the best candidate: {save_alignment_html(result, args.html)}")
    if best is None:
        print(
            f"no candidate: no sample earned a goal reward within {args.samples} samples; "
            f"wrote {args.out / ALIGNMENT_JSON} (empty candidate list), no {ALIGNED_DEMO_NPZ}. "
            "Try more --samples or another --seed.",
            file=sys.stderr,
        )
        return 1
    print(
        f"best: sample {best.index}, mean goal reward {best.reward:.3f} "
        f"(scale {best.sample.scale}, z offset {best.sample.z_offset:+.3f} m)"
    )
    robot = tool_record(args.tool).default_robots.get(args.world, "ROBOT")  # the record's robot for this world
    print(
        f"wrote {args.out / ALIGNMENT_JSON}, {args.out / CANDIDATES_NPZ} and {args.out / ALIGNED_DEMO_NPZ}; next: "
        f"toolimit trajopt --robot {robot} --tool {args.tool} --alignment {args.out} --out {args.out}_{robot}"
    )
    return 0
