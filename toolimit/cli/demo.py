"""``toolimit demo``: make a synthetic demonstration (``synth``) or summarise one (``show``)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from toolimit.cli import (
    CliError,
    add_out_argument,
    add_seed_argument,
    add_tool_argument,
    check_choice,
    check_count,
    check_writable_folder,
)

if TYPE_CHECKING:
    from toolimit.demos import ToolDemo


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("demo", help="synthetic demonstrations and demo summaries (stage i)")
    actions = parser.add_subparsers(dest="action", required=True)

    synth = actions.add_parser("synth", help="write a synthetic demonstration (.npz)")
    add_tool_argument(synth)
    add_seed_argument(synth)
    synth.add_argument("--fps", type=float, default=24.0, help="frames per second (default: 24)")
    add_out_argument(synth, "output .npz file")
    synth.set_defaults(func=run_synth)

    show = actions.add_parser("show", help="print a demonstration's summary and keypoints, as loaded and cleaned")
    show.add_argument("path", type=Path, help="demonstration file")
    show.add_argument("--tool", default=None, help="tool name, for files that do not store it")
    show.set_defaults(func=run_show)


def run_synth(args: argparse.Namespace) -> int:
    from toolimit.demos import save_demo, synthesize_demo
    from toolimit.demos.synthetic import synthetic_tools

    check_choice("--tool", args.tool, synthetic_tools(), "tool")
    check_count("--seed", args.seed, minimum=0)
    if not args.fps > 0:
        raise CliError(f"--fps: must be positive, got {args.fps}")
    if args.out.suffix != ".npz":
        raise CliError(f"--out: expected a .npz file name, got {args.out}")
    check_writable_folder(args.out.parent, "--out")
    demo = synthesize_demo(args.tool, args.seed, fps=args.fps)
    save_demo(demo, args.out)
    print(f"wrote {args.out}: {summary(demo)}")
    return 0


def run_show(args: argparse.Namespace) -> int:
    from toolimit.align.keypoints import velocity_keypoints
    from toolimit.demos import clean_demo, load_demo
    from toolimit.errors import DemoError

    demo = load_demo(args.path, tool=args.tool)
    print(f"{args.path}: {demo.tool}, {demo.n_frames} frames at {demo.fps:g} fps ({demo.duration:.2f} s)")
    if demo.source:
        print(f"source: {demo.source}")
    print(f"as loaded (raw): {_motion(demo)}, keypoints (frames) {velocity_keypoints(demo).tolist()}")
    try:
        cleaned, report = clean_demo(demo)
    except DemoError as error:  # `toolimit align` would refuse it the same way; --no-clean aligns it raw
        print(f"cleaned: not possible ({error})")
        return 0
    print(
        f"cleaned, as `toolimit align` uses it ({len(report.replaced_frames)} frames replaced, "
        f"{len(report.head_replaced_frames)} of them with the head's position): {_motion(cleaned)}, "
        f"keypoints (frames) {velocity_keypoints(cleaned).tolist()}"
    )
    return 0


def _motion(demo: ToolDemo) -> str:
    return f"tool length {demo.length:.3f} m, peak speed {demo.speed().max():.2f} m/s"


def summary(demo: ToolDemo) -> str:
    """One line: tool, frames, fps, duration, tool length and peak speed."""
    return (
        f"{demo.tool}, {demo.n_frames} frames at {demo.fps:g} fps ({demo.duration:.2f} s), "
        f"tool length {demo.length:.3f} m, peak speed {demo.speed().max():.2f} m/s"
    )
