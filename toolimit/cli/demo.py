"""``toolimit demo``: make a synthetic demonstration (``synth``), summarise one (``show``), or go
from a video to one: ``render`` a demonstration to an MP4, ``track`` its markers to a tracks CSV,
``lift`` tracks to a demonstration (:mod:`toolimit.demos.video`)."""

from __future__ import annotations

import argparse
import importlib
from dataclasses import replace
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from toolimit.cli import (
    CliError,
    add_out_argument,
    add_seed_argument,
    add_tool_argument,
    check_choice,
    check_count,
    check_output_file,
    check_writable_folder,
)
from toolimit.cli.flags import Flag, add_flags, apply_flags
from toolimit.demos.tool_demo import frame_rate_problem
from toolimit.demos.video.lift import HANDLE_HINTS, LiftSettings

if TYPE_CHECKING:
    from toolimit.demos import ToolDemo
    from toolimit.demos.video import EndpointTracks


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

    render = actions.add_parser(
        "render", help="render a demonstration to an MP4 (tool stick, end markers, ground grid, a figure)"
    )
    render.add_argument("demo", type=Path, help="demonstration file")
    render.add_argument("--tool", default=None, help="tool name, for files that do not store it")
    render.add_argument(
        "--camera",
        type=Path,
        default=None,
        help="camera JSON to film with (default: a side camera 3.5 m from the motion, 1.2 m high, 1280 x 720, "
        "f = 1000 px, written to OUT's name with .camera.json)",
    )
    add_out_argument(render, "output .mp4 file; the true tracks go beside it (.truth.csv)")
    render.set_defaults(func=run_render)

    track = actions.add_parser("track", help="track a rendered video's two end markers to a tracks CSV")
    track.add_argument("video", type=Path, help="video file (.mp4) made by `toolimit demo render`")
    add_out_argument(track, "output tracks .csv file")
    track.set_defaults(func=run_track)

    lift = actions.add_parser("lift", help="lift a tracks CSV seen by a calibrated camera to a demonstration (.npz)")
    lift.add_argument(
        "tracks", type=Path, help="tracks CSV: frame,head_u,head_v,handle_u,handle_v,head_visible,handle_visible"
    )
    lift.add_argument("--camera", type=Path, required=True, help="camera JSON: width, height, K, world_from_camera")
    add_tool_argument(lift)
    lift.add_argument("--fps", type=float, required=True, help="the video's frames per second")
    add_flags(lift, LIFT_FLAGS, {"": LiftSettings()})
    add_out_argument(lift, "output .npz demonstration")
    lift.set_defaults(func=run_lift)


def _point(text: str) -> tuple[float, float, float]:
    """``x,y,z`` metres -> a point (argparse type)."""
    try:
        values = tuple(float(value) for value in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected x,y,z in metres, got {text!r}") from None
    if len(values) != 3:
        raise argparse.ArgumentTypeError(f"expected three coordinates x,y,z, got {text!r}")
    return values  # type: ignore[return-value]


def _direction(text: str) -> tuple[float, float]:
    """``x,y`` -> a horizontal direction (argparse type)."""
    try:
        values = tuple(float(value) for value in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected x,y, got {text!r}") from None
    if len(values) != 2:
        raise argparse.ArgumentTypeError(f"expected two coordinates x,y, got {text!r}")
    return values  # type: ignore[return-value]


#: ``toolimit demo lift``'s flags: the fields of :class:`LiftSettings` a user sets.
LIFT_FLAGS = (
    Flag("handle_hint", choices=HANDLE_HINTS),
    Flag("tool_length"),
    Flag("plane_point", parse=_point, show=lambda point: "from the ground contacts" if point is None else str(point)),
    Flag(
        "plane_normal",
        parse=_direction,
        show=lambda normal: "the camera's viewing direction" if normal is None else str(normal),
    ),
    Flag("fit_plane_normal"),
    Flag("contact_share"),
    Flag("pixel_noise"),
    Flag("smoothing", show=lambda width: "chosen for each end by cross-validation" if width is None else str(width)),
    Flag("offset_smoothing"),
)


def run_synth(args: argparse.Namespace) -> int:
    from toolimit.demos import save_demo, synthesize_demo
    from toolimit.demos.synthetic import synthetic_tools

    check_choice("--tool", args.tool, synthetic_tools(), "tool")
    check_count("--seed", args.seed, minimum=0)
    if problem := frame_rate_problem(args.fps):
        raise CliError(f"--fps: {problem}")
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


def run_render(args: argparse.Namespace) -> int:
    from toolimit.demos import load_demo
    from toolimit.demos.video import read_camera, side_camera, write_camera, write_tracks

    check_output_file(args.out, "--out", ".mp4")
    demo = load_demo(args.demo, tool=args.tool)
    camera = read_camera(args.camera) if args.camera is not None else side_camera(demo.head)
    render_video = _video_module("render").render_video
    truth = render_video(demo, camera, args.out)
    truth_path = args.out.with_suffix(".truth.csv")
    write_tracks(truth, truth_path)
    written = [str(args.out), str(truth_path)]
    if args.camera is None:
        camera_path = args.out.with_suffix(".camera.json")
        write_camera(camera, camera_path)
        written.append(str(camera_path))
    print(
        f"wrote {', '.join(written)}: {demo.n_frames} frames at {demo.fps:g} fps, {camera.width} x {camera.height} px; "
        f"{_seen(truth)} (not hidden by the figure)"
    )
    return 0


def run_track(args: argparse.Namespace) -> int:
    from toolimit.demos.video import write_tracks

    check_output_file(args.out, "--out", ".csv")
    if not args.video.is_file():
        raise CliError(f"video file not found: {args.video}")
    tracks = _video_module("marker_tracking").track_markers(args.video)
    write_tracks(tracks, args.out)
    print(f"wrote {args.out}: {tracks.n_frames} frames; {_seen(tracks)}")
    return 0


def run_lift(args: argparse.Namespace) -> int:
    from toolimit.demos.video import lift_tracks, read_camera, read_tracks
    from toolimit.demos.video.lifted_file import side_summary, write_lifted

    check_choice("--tool", args.tool, _tools(), "tool")
    if problem := frame_rate_problem(args.fps):
        raise CliError(f"--fps: {problem}")
    check_output_file(args.out, "--out", ".npz")
    settings = apply_flags(LiftSettings(), LIFT_FLAGS, args)
    for option, path in (("tracks", args.tracks), ("--camera", args.camera)):
        if not path.is_file():
            raise CliError(f"{option}: file not found: {path}")
    tracks = read_tracks(args.tracks)
    camera = read_camera(args.camera)
    lifted = lift_tracks(tracks, camera, args.tool, args.fps, settings)
    demo = replace(lifted.demo, source=f"lifted from {args.tracks} seen by {args.camera}")
    write_lifted(lifted, demo, args.out)
    print(
        f"wrote {args.out}: {summary(demo)}; working plane {lifted.plane_distance:.2f} m from the camera, "
        f"its normal turned {lifted.plane_turn:+.0f} deg from the camera's viewing direction; "
        f"filled in: head {int(lifted.head_filled.sum())}, handle end {int(lifted.handle_filled.sum())} frames"
    )
    print(side_summary(lifted.side_source, lifted.side_margin, lifted.mirror_distance))
    print(
        f"uncertainty (1 sigma, median over frames): head {np.median(lifted.head_sigma) * 100:.1f} cm, handle end "
        f"{np.median(lifted.handle_sigma) * 100:.1f} cm if its side is right, "
        f"{np.median(lifted.mirror_distance) * 100:.0f} cm if not; the motion leaving its plane is not included"
    )
    return 0


def _tools() -> list[str]:
    from toolimit.tools import TOOLS

    return list(TOOLS)


def _seen(tracks: EndpointTracks) -> str:
    return f"head seen in {int(tracks.head_visible.sum())}, handle end in {int(tracks.handle_visible.sum())} frames"


def _video_module(name: str) -> ModuleType:
    """``toolimit.demos.video.<name>``, which needs OpenCV: a one-line error naming the extra when it is missing."""
    try:
        return importlib.import_module(f"toolimit.demos.video.{name}")
    except ModuleNotFoundError as error:
        if error.name != "cv2":
            raise
        raise CliError('OpenCV is not installed: install the video extra (pip install -e ".[video]")') from None


def _motion(demo: ToolDemo) -> str:
    return f"tool length {demo.length:.3f} m, peak speed {demo.speed().max():.2f} m/s"


def summary(demo: ToolDemo) -> str:
    """One line: tool, frames, fps, duration, tool length and peak speed."""
    return (
        f"{demo.tool}, {demo.n_frames} frames at {demo.fps:g} fps ({demo.duration:.2f} s), "
        f"tool length {demo.length:.3f} m, peak speed {demo.speed().max():.2f} m/s"
    )
