"""``toolimit align``: find scene parameters under which a demonstration reaches the goal.

The command line of :func:`toolimit.pipeline.align_stage`; its flags are the fields of
:class:`toolimit.pipeline.AlignSettings`. Writes ``DIR/alignment.json`` (the search's record),
``DIR/candidates.npz`` and ``DIR/aligned_demo.npz`` (the best candidate's aligned motion); ``--ray``
evaluates batches of samples on a Ray cluster (same candidates); optionally a rerun recording (``--rerun``) and, in the 3d world, the
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
    add_ray_argument,
    add_scene_arguments,
    check_output_file,
    check_output_folder,
    check_ray,
    check_scene,
    check_writable_folder,
)
from toolimit.cli.flags import Flag, add_flags, apply_flags, show_workers
from toolimit.pipeline.settings import AlignSettings

#: The search's budget, shared with ``toolimit run`` (fields of :class:`AlignSettings`).
SEARCH_FLAGS = (Flag("search.samples"), Flag("search.candidates"), Flag("search.z_offset_std"))
#: Every flag of ``toolimit align`` built from its settings.
ALIGN_FLAGS = (*SEARCH_FLAGS, Flag("seed"), Flag("workers", show=show_workers), Flag("clean"))


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "align",
        help="align a scene to a demonstration (stage ii)",
        description=__doc__.splitlines()[0],
    )
    add_scene_arguments(parser, "planar")
    parser.add_argument(
        "--demo",
        required=True,
        type=Path,
        help="demonstration file (project .npz, real aligned .npz or estimator .pkl)",
    )
    add_flags(parser, ALIGN_FLAGS, {"": AlignSettings()})
    add_out_argument(parser)
    parser.add_argument("--rerun", type=Path, default=None, help="also save a rerun recording (.rrd) here")
    parser.add_argument(
        "--html",
        type=Path,
        default=None,
        help="3d world only: also save the best candidate's replay as a self-contained meshcat page (.html)",
    )
    add_ray_argument(parser, "batches of samples as tasks")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def _check_arguments(args: argparse.Namespace) -> AlignSettings:
    """Validate before any work; returns the settings."""
    check_scene(args.tool, args.world)
    settings = apply_flags(AlignSettings(), ALIGN_FLAGS, args)
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
    check_ray(args.ray)
    return settings


def run(args: argparse.Namespace) -> int:
    from toolimit.align.outputs import ALIGNED_DEMO_NPZ, ALIGNMENT_JSON, CANDIDATES_NPZ, CHECKPOINT_JSON
    from toolimit.align.search import SearchInterrupted
    from toolimit.pipeline.stages import align_stage, describe_alignment
    from toolimit.tools import tool_record

    settings = _check_arguments(args)
    checkpoint = args.out / CHECKPOINT_JSON
    if checkpoint.is_file():
        print(f"found {checkpoint}: the search resumes from it if it was made with the same settings")
    try:
        result = align_stage(
            args.demo, args.tool, args.world, args.out, settings, progress=not args.quiet, ray=args.ray
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
    for line in describe_alignment(result):
        print(line)
    if args.rerun is not None:
        from toolimit.viz.rerun_alignment import save_alignment_recording

        written = save_alignment_recording(result, args.rerun)
        print(f"rerun recording: {args.rerun}" if written else "rerun recording skipped (RERUN=off)")
    if args.html is not None:
        from toolimit.viz.meshcat_alignment import save_alignment_html

        print(f"meshcat replay of the best candidate: {save_alignment_html(result, args.html)}")
    robot = tool_record(args.tool).default_robots.get(args.world, "ROBOT")  # the record's robot for this world
    print(
        f"wrote {args.out / ALIGNMENT_JSON}, {args.out / CANDIDATES_NPZ} and {args.out / ALIGNED_DEMO_NPZ}; next: "
        f"toolimit trajopt --robot {robot} --tool {args.tool} --alignment {args.out} --out {args.out}_{robot}"
    )
    return 0
