"""``toolimit evaluate``: roll a learned policy out over many seeds and report its success.

Reads POLICY/policy.safetensors and POLICY/task.npz (``toolimit learn``'s folder); a
stable-baselines3 POLICY/policy.zip (an earlier toolimit's) only with ``--trust-sb3-zip``, since
loading one unpickles it and can run code. Writes ``--out``
(default POLICY/evaluation.json): deterministic and stochastic rollouts, each with
``success_rate`` (the paper's criterion), ``goal_reward_mean``, ``goal_reward`` per episode and
``episodes``. A policy learned with ``--adr`` is evaluated with the goal box at the aligned position.

``--heat-map OUT.svg`` (spades) also rolls the policy out deterministically with the goal box at
each of ``--grid`` x ``--grid`` positions over 1.5 times the ADR range (100 x 90 cm around the
aligned position; one row in the planar world, whose box has no y) and writes the spheres
delivered per position as an SVG picture with the robot's reach drawn
(:mod:`toolimit.learn.heat_map`, :mod:`toolimit.viz.svg_heat_map`); its values go into the report
under ``heat_map``, and ``--rerun OUT.rrd`` logs the map to a rerun recording. Exit codes: 0 done,
2 bad input.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from toolimit.cli import CliError, check_output_file, check_writable_folder
from toolimit.cli.flags import Flag, add_flags, apply_flags
from toolimit.learn.heat_map import EPISODES_PER_CELL
from toolimit.pipeline.settings import EvaluationSettings

if TYPE_CHECKING:
    from toolimit.pipeline.stages import PolicyEvaluation

#: Every flag of ``toolimit evaluate`` built from its settings.
EVALUATION_FLAGS = (Flag("episodes"), Flag("seed"))


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "evaluate", help="evaluate a learned policy over many seeds", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--policy", required=True, type=Path, help="`toolimit learn` output folder")
    parser.add_argument(
        "--trust-sb3-zip",
        action="store_true",
        help="read a stable-baselines3 POLICY/policy.zip: its loading unpickles it and CAN RUN CODE; "
        "only for a file whose author you trust",
    )
    add_flags(parser, EVALUATION_FLAGS, {"": EvaluationSettings()})
    parser.add_argument("--out", type=Path, default=None, help="JSON report (default: POLICY/evaluation.json)")
    parser.add_argument(
        "--heat-map", type=Path, default=None, help="also write the goal-box heat map to this .svg (spades)"
    )
    parser.add_argument("--grid", type=int, default=9, help="with --heat-map: box positions per axis (default: 9)")
    parser.add_argument(
        "--heat-map-episodes",
        type=int,
        default=None,
        help=f"with --heat-map: deterministic episodes per position (default: {EPISODES_PER_CELL})",
    )
    parser.add_argument("--rerun", type=Path, default=None, help="with --heat-map: also log it to this .rrd")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from toolimit.artifacts import save_json
    from toolimit.pipeline.stages import EVALUATION_JSON, evaluate_stage

    settings = apply_flags(EvaluationSettings(), EVALUATION_FLAGS, args)
    if not args.policy.is_dir():
        raise CliError(f"--policy: no such folder: {args.policy}")
    out = args.out or args.policy / EVALUATION_JSON
    check_writable_folder(out.parent, "--out")
    if args.heat_map is None and args.rerun is not None:
        raise CliError("--rerun: needs --heat-map OUT.svg")
    check_output_file(args.heat_map, "--heat-map", ".svg")
    check_output_file(args.rerun, "--rerun", ".rrd")
    if args.grid < 2:
        raise CliError(f"--grid: must be an integer >= 2, got {args.grid}")
    if args.heat_map_episodes is not None and args.heat_map_episodes < 1:
        raise CliError(f"--heat-map-episodes: must be an integer >= 1, got {args.heat_map_episodes}")
    evaluation = evaluate_stage(args.policy, settings, args.trust_sb3_zip)
    record = evaluation.record
    if args.heat_map is not None:
        record["heat_map"] = _heat_map(args, evaluation, settings.seed)
    save_json(out, record)
    print(
        f"success rate {record['success_rate']:.2f} (deterministic), {record['stochastic']['success_rate']:.2f} "
        f"(stochastic) over {settings.episodes} episodes; goal reward {record['goal_reward_mean']:.1f}; wrote {out}"
    )
    return 0


def _heat_map(args: argparse.Namespace, evaluation: PolicyEvaluation, seed: int) -> dict:
    """Compute the heat map of ``args.policy``, write its SVG (and rerun recording); its record."""
    from toolimit.artifacts import save_text
    from toolimit.learn.heat_map import goal_box_heat_map
    from toolimit.viz.rerun_heat_map import save_heat_map_recording
    from toolimit.viz.svg_heat_map import heat_map_svg

    task = evaluation.task
    episodes = EPISODES_PER_CELL if args.heat_map_episodes is None else args.heat_map_episodes
    heat_map = goal_box_heat_map(evaluation.model, task, grid=args.grid, episodes=episodes, seed=seed)
    kind = "learned with ADR" if heat_map.observes_box else "learned without ADR (the box is not observed)"
    save_text(args.heat_map, heat_map_svg(heat_map, f"{task.robot} {task.tool} ({task.world}), policy {kind}"))
    if args.rerun is not None:
        save_heat_map_recording(heat_map, args.rerun)
    record = heat_map.record()
    print(
        f"heat map over {heat_map.goal_rewards.size} box positions: the box can stand at {record['standing']}, "
        f"the policy succeeds at {record['succeeding']} ({record['succeeding_in_rectangle']} of "
        f"{record['standing_in_rectangle']} inside the ADR rectangle, {record['succeeding_reachable_in_rectangle']} of "
        f"the {record['standing_reachable_in_rectangle']} there within the robot's reach); wrote {args.heat_map}"
    )
    return record
