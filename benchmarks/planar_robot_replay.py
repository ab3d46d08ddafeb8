"""Tool-only replay vs robot replay in the planar spade world, on the five shipped spade demos.

For each demo: planar alignment (K candidates), then the planar 3-link arm tracks every candidate
and replays its joint trajectory in the candidate's scene; the candidate whose robot replay earns
the most goal reward is selected (the paper's selection by robot execution). Prints, per demo, the
best tool-only reward, the selected candidate's robot reward and how many candidates the arm
reproduced, and writes benchmarks/results/planar_robot_replay.json.

    python benchmarks/planar_robot_replay.py [--candidates 5] [--velocity-weight 1e-4]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from toolimit.align import AlignmentConfig
from toolimit.align.search import align
from toolimit.artifacts import save_json
from toolimit.demos import clean_demo, load_demo
from toolimit.robots import make_robot
from toolimit.trajopt import PoseTargets, TrackingWeights, TrackOptions
from toolimit.trajopt.selection import AlignedCandidate, select_by_robot_execution

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--candidates", type=int, default=5)
    parser.add_argument("--velocity-weight", type=float, default=1e-4)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    robot = make_robot("planar3", tool="spade")
    options = TrackOptions(weights=TrackingWeights(velocity=args.velocity_weight))
    rows = []
    print(f"{'demo':10} {'tool-only best':>14} {'robot best':>10} {'reproduced':>10} {'time s':>7}")
    for i in range(5):
        started = time.perf_counter()
        demo, _ = clean_demo(load_demo(ROOT / "data" / "demos" / f"spade_{i:02d}.npz"))
        result = align(demo, "spade", "planar", AlignmentConfig(candidates=args.candidates), seed=0,
                       workers=args.workers, progress=False, clean=False)
        candidates = []
        for candidate in result.candidates:
            _, _, poses = result.aligned_motion(candidate)
            targets = PoseTargets(np.asarray(poses.position), np.asarray(poses.rotation), fps=result.demo.fps)
            candidates.append(AlignedCandidate(targets, candidate.sample.params, candidate.reward))
        selection = select_by_robot_execution(robot, candidates, "spade", "planar", options, progress=False)
        robot_rewards = np.nan_to_num(selection.robot_rewards, nan=0.0)
        row = {
            "demo": f"spade_{i:02d}",
            "tool_only_rewards": [c.alignment_reward for c in candidates],
            "robot_rewards": robot_rewards.tolist(),
            "selected": selection.best,
            "wall_time_s": time.perf_counter() - started,
        }
        rows.append(row)
        print(f"{row['demo']:10} {max(row['tool_only_rewards']):14.1f} {robot_rewards.max():10.1f} "
              f"{int((robot_rewards > 0).sum()):>5} of {len(candidates)} {row['wall_time_s']:7.1f}")
    save_json(ROOT / "benchmarks" / "results" / "planar_robot_replay.json",
              {"velocity_weight": args.velocity_weight, "candidates": args.candidates, "runs": rows})


if __name__ == "__main__":
    main()
