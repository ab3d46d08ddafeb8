"""``toolimit evaluate``: roll a learned policy out over many seeds and report its success.

Reads POLICY/policy.zip and POLICY/task.npz (``toolimit learn``'s folder). Writes ``--out``
(default POLICY/evaluation.json): deterministic and stochastic rollouts, each with
``success_rate`` (the paper's criterion), ``goal_reward_mean``, ``goal_reward`` per episode and
``episodes``. Exit codes: 0 done, 2 bad input.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from toolimit.cli import CliError, add_seed_argument, check_writable_folder

if TYPE_CHECKING:
    from toolimit.learn.evaluate import Evaluation
    from toolimit.learn.task import LearningTask

EVALUATION_JSON = "evaluation.json"


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "evaluate", help="evaluate a learned policy over many seeds", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--policy", required=True, type=Path, help="`toolimit learn` output folder")
    parser.add_argument("--episodes", type=int, default=20, help="episodes per mode (default: 20)")
    add_seed_argument(parser, "seed of the evaluation episodes", default=1000)
    parser.add_argument("--out", type=Path, default=None, help="JSON report (default: POLICY/evaluation.json)")
    parser.set_defaults(func=run)


def evaluation_record(policy_dir: Path, episodes: int, seed: int) -> tuple[dict, Evaluation, LearningTask]:
    """Deterministic and stochastic evaluations of the policy in ``policy_dir``: the JSON record,
    the deterministic evaluation (its joint trajectories serve the export) and the task."""
    from toolimit.learn.evaluate import evaluate
    from toolimit.learn.training import load_policy

    model, task = load_policy(policy_dir)
    deterministic = evaluate(model, task, episodes, deterministic=True, seed=seed)
    stochastic = evaluate(model, task, episodes, deterministic=False, seed=seed)
    record = {
        "tool": task.tool,
        "world": task.world,
        "robot": task.robot,
        "seed": seed,
        **deterministic.record(),
        "stochastic": stochastic.record(),
    }
    return record, deterministic, task


def run(args: argparse.Namespace) -> int:
    from toolimit.artifacts import save_json

    if args.episodes < 1:
        raise CliError(f"--episodes: must be >= 1, got {args.episodes}")
    if not args.policy.is_dir():
        raise CliError(f"--policy: no such folder: {args.policy}")
    out = args.out or args.policy / EVALUATION_JSON
    check_writable_folder(out.parent, "--out")
    record, _, _ = evaluation_record(args.policy, args.episodes, args.seed)
    save_json(out, record)
    print(
        f"success rate {record['success_rate']:.2f} (deterministic), {record['stochastic']['success_rate']:.2f} "
        f"(stochastic) over {args.episodes} episodes; goal reward {record['goal_reward_mean']:.1f}; wrote {out}"
    )
    return 0
