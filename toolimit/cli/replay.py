"""``toolimit replay``: replay a tool motion in a scene with given parameters and report what it earned.

For checking a scene by hand: the poses (``tip_position`` (T, 3) m, ``tip_quaternion_wxyz``
(T, 4), ``fps``; world frame, toolimit's tool frame or, with ``--frame original-spade``, the
original code's spade tip frame) are replayed tool-only ``--replays`` times as one batch of
instances, each with its own randomness (seed ``--seed``). The scene parameters come from a JSON
object of the scene's parameter names (positions as [x, y, z] lists in metres, angles in radians)
or, for the original authors' aligned files, from the poses file itself (``--params-from-poses``:
``sand_buffer_position``, ``sand_buffer_yaw``, ``goal_box_position``, ``nail_position``).

Prints one line per replay set; ``--json`` writes ``goal_reward`` (the final goal reward of every
replay), ``goal_reward_mean`` and ``success_rate`` (the scene's success test at the end) with the
inputs; ``--html`` writes the first replay as a self-contained meshcat page (3d world). Exit codes:
0 done, 2 bad input (one line, nothing written).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from toolimit.artifacts import load_npz
from toolimit.cli import (
    CliError,
    add_frame_argument,
    add_scene_arguments,
    add_seed_argument,
    check_count,
    check_scene,
    load_poses,
)
from toolimit.demos.npz_format import ORIGINAL_PARAMETER_NAMES, original_scene_params


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "replay",
        help="replay a tool motion in a scene and report its goal reward",
        description="Replay a tool motion (poses file) tool-only in a scene with given parameters, "
        "several times, and report the goal reward each replay earned.",
    )
    add_scene_arguments(parser, "3d")
    parser.add_argument("--poses", required=True, type=Path, help=".npz with tip_position, tip_quaternion_wxyz, fps")
    add_frame_argument(parser)
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--params", type=Path, help="JSON object of the scene's parameters")
    source.add_argument(
        "--params-from-poses",
        action="store_true",
        help="read the parameters from the poses file (the original aligned files' names: "
        + ", ".join(ORIGINAL_PARAMETER_NAMES)
        + ")",
    )
    parser.add_argument("--replays", type=int, default=10, help="replays, one batch (default: 10)")
    add_seed_argument(parser)
    parser.add_argument("--html", type=Path, default=None, help="3d world only: save the first replay as .html")
    parser.add_argument("--json", type=Path, default=None, help="save the figures as .json")
    parser.set_defaults(func=run)


def _check_arguments(args: argparse.Namespace) -> None:
    """Validate the options that need no file (before any work)."""
    check_scene(args.tool, args.world)
    check_count("--replays", args.replays)
    check_count("--seed", args.seed, minimum=0)
    if args.frame == "original-spade" and args.tool != "spade":
        raise CliError(f"--frame original-spade: only for the spade, not {args.tool}")
    if args.html is not None:
        if args.world != "3d":
            raise CliError("--html: only for the 3d world")
        if args.html.suffix != ".html":
            raise CliError(f"--html: expected a .html file name, got {args.html}")
    if args.json is not None and args.json.suffix != ".json":
        raise CliError(f"--json: expected a .json file name, got {args.json}")
    if not args.poses.is_file():
        raise CliError(f"--poses: no such file: {args.poses}")


def _params_from_json(path: Path, specs) -> dict:
    """The scene parameters in a JSON object; positions become (3,) arrays."""
    if not path.is_file():
        raise CliError(f"--params: no such file: {path}")
    try:
        data = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise CliError(f"--params: {path} is not valid JSON ({error})") from None
    if not isinstance(data, dict):
        raise CliError(f"--params: {path} must hold a JSON object of parameter names, got {type(data).__name__}")
    names = {spec.name: spec for spec in specs}
    unknown = sorted(set(data) - set(names))
    if unknown:
        raise CliError(f"--params: {path}: unknown parameters {unknown}; the scene's are {sorted(names)}")
    params = {}
    for name, value in data.items():
        try:
            array = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise CliError(f"--params: {path}: {name} must be numbers, got {value!r}") from None
        params[name] = array if names[name].kind == "position" else (float(array) if array.shape == () else array)
    return params


def _params_from_poses(path: Path, specs) -> dict:
    """The scene parameters stored in an original aligned poses file, under the scenes' names."""
    wanted = {spec.name for spec in specs}
    found = {name: value for name, value in original_scene_params(load_npz(path)).items() if name in wanted}
    missing = sorted(wanted - set(found))
    if missing:
        keys = sorted(key for key, name in ORIGINAL_PARAMETER_NAMES.items() if name in missing)
        raise CliError(f"--params-from-poses: {path} lacks {keys} (the scene needs {missing})")
    return found


def run(args: argparse.Namespace) -> int:
    from toolimit.artifacts import save_json
    from toolimit.scenes.registry import make_scene
    from toolimit.scenes.replay import replay

    _check_arguments(args)
    targets = load_poses(args.poses, args.frame)
    scene = make_scene(args.tool, args.world)
    if abs(targets.fps * scene.control_dt - 1.0) > 1e-6:
        raise CliError(
            f"--poses: {args.poses} is at {targets.fps:g} fps; the scene steps at {1 / scene.control_dt:g} fps"
        )
    params = (
        _params_from_poses(args.poses, scene.parameters)
        if args.params_from_poses
        else _params_from_json(args.params, scene.parameters)
    )
    reason = scene.invalid_reason(params)
    if reason is not None:
        raise CliError(f"scene parameters: {reason}")

    rewards = replay(scene, params, np.random.default_rng(args.seed), targets.poses, args.replays)
    success = np.asarray(scene.is_success(), dtype=bool)
    print(
        f"toolimit replay: {args.tool} {args.world}, {len(targets.positions)} frames x {args.replays} replays: "
        f"goal reward mean {rewards.mean():.2f} (min {rewards.min():g}, max {rewards.max():g}), "
        f"success rate {success.mean():.2f}"
    )
    if args.json is not None:
        save_json(
            args.json,
            {
                "tool": args.tool,
                "world": args.world,
                "poses": str(args.poses),
                "frame": args.frame,
                "params": {name: np.asarray(value).tolist() for name, value in params.items()},
                "replays": args.replays,
                "seed": args.seed,
                "frames": len(targets.positions),
                "goal_reward": rewards.tolist(),
                "goal_reward_mean": float(rewards.mean()),
                "success_rate": float(success.mean()),
            },
        )
    if args.html is not None:
        from toolimit.viz.meshcat_views import scene_replay_html

        scene_replay_html(
            args.html, make_scene(args.tool, args.world), targets.poses, params, np.random.default_rng(args.seed)
        )
    return 0
