"""How far a cell's 20-episode success rate moves with the evaluation's seed.

The learning task's reset noise moves every position parameter of the scene (the spade's deposit
and box, the nail, the scythe's patch) by N(0, 1 cm) in x and y, each instance its own draw
(``toolimit.learn.simulator``; until the per-instance noise, one draw per batch, so that a cell's
20 episodes shared one draw and its success rate moved with it: dense PPO on ``spade_02`` gave
0.40-0.60 over five evaluation seeds and 0.36 over 100 draws). This script re-evaluates every
learnt policy of a full reproduction two ways, deterministically:

- ``batches``: the figure's evaluation (20 episodes) on ``--batch-seeds`` seeds, the first of them
  the figure's own (1000): the spread across seeds;
- ``long``: ``--episodes`` episodes from seed ``--seed``: what the policy does over the noise.

With a draw per episode the spread is that of 20 Bernoulli trials: a policy of success p moves by
about sqrt(p (1 - p) / 20) (0.11 at p = 0.5). It prints one line per policy and writes ``--out``
(JSON). About 10 s per 3D spade policy on one core, a second or two for the hammer and the scythe.

    python benchmarks/evaluation_noise.py --reproduction runs/reproduce/seed_0 --out benchmarks/results/evaluation_noise.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from toolimit.learn.evaluate import EVALUATION_SEED, evaluate
from toolimit.learn.training import load_policy

#: The learning cells and their folders in an experiment's folder of ``toolimit reproduce``.
POLICY_FOLDERS = {
    "final": "method/learning",
    "lfd": "lfd/learning",
    "sparse_ppo": "sparse_ppo",
    "dense_ppo": "dense_ppo",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--reproduction", type=Path, required=True, help="a seed's folder of a `toolimit reproduce --preset full`"
    )
    parser.add_argument("--episodes", type=int, default=100, help="episodes of the long evaluation")
    parser.add_argument("--seed", type=int, default=5000, help="seed of the long evaluation")
    parser.add_argument("--batch-seeds", type=int, default=5, help="seeds of the 20-episode evaluation: 1000, 1001, ...")
    parser.add_argument("--out", type=Path, required=True, help="JSON file written")
    args = parser.parse_args()
    cells = json.loads((args.reproduction / "results.json").read_text())["cells"]
    rows = []
    for cell in cells:
        if cell["method"] not in POLICY_FOLDERS:
            continue
        experiment = "-".join((cell["tool"], cell["world"], cell["robot"], cell["demo"]))
        model, task = load_policy(args.reproduction / experiment / POLICY_FOLDERS[cell["method"]])
        batches = [
            evaluate(model, task, 20, deterministic=True, seed=EVALUATION_SEED + k).record()["success_rate"]
            for k in range(args.batch_seeds)
        ]
        long = evaluate(model, task, args.episodes, deterministic=True, seed=args.seed).record()
        success, goal = long["success_rate"], long["goal_reward_mean"]
        row = {
            "experiment": experiment,
            "method": cell["method"],
            "figure": {"success_rate": cell["success_rate"], "goal_reward": cell["goal_reward"]},
            "batches": {
                "episodes": 20,
                "seeds": [EVALUATION_SEED + k for k in range(args.batch_seeds)],
                "success_rates": batches,
            },
            "long": {"episodes": args.episodes, "seed": args.seed, "success_rate": success, "goal_reward": goal},
        }
        rows.append(row)
        print(
            f"{experiment} {cell['method']}: figure {cell['success_rate']:.2f}; 20 episodes on "
            f"{args.batch_seeds} seeds {min(batches):.2f}-{max(batches):.2f}; {args.episodes} episodes "
            f"{success:.2f} ({goal:.2f})",
            flush=True,
        )
    args.out.write_text(
        json.dumps({"what": __doc__.splitlines()[0], "reproduction": str(args.reproduction), "cells": rows}, indent=1)
        + "\n"
    )
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
