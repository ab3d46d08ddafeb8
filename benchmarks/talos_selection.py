"""The Talos's stage-iii selection on the authors' real spade recording: with and without the
authors' tool-roll joint, at their height (pelvis 0.3 m above the scene) and at the former knee
height (0.619 m).

Aligns the recording once (the 3D spade scene, ``--candidates`` K, seed 0), then tracks every
candidate with each Talos variant and replays it in its scene (10 replays): prints the best robot
replay's spheres, how many candidates earn, and the share of the kept trajectory's steps at which
the wrist (arm joint 7) and the tool roll stand within 5 % of their range of a limit.

    flock /work/heavy.lock python benchmarks/talos_selection.py --out /tmp/talos --json results.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from toolimit.align.config import AlignmentConfig
from toolimit.pipeline.settings import AlignSettings, TrajoptSettings
from toolimit.pipeline.stages import align_stage
from toolimit.robots import arms
from toolimit.robots.model import build_robot_model
from toolimit.tools import tool_spec
from toolimit.trajopt.selection import load_candidates, select_by_robot_execution

RECORDING = Path(__file__).resolve().parents[1] / "../shared/data/video_demos/spade_video1_aligned.npz"
#: (label, with the tool roll, pelvis height above the scene in m)
VARIANTS = (
    ("tool roll, 0.30 m", True, 0.3),
    ("no tool roll, 0.30 m", False, 0.3),
    ("no tool roll, 0.619 m", False, 0.619),
)
#: A joint is "near" its limit within this fraction of its range.
NEAR = 0.05


def limit_shares(q: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(N,) share of the trajectory's configurations (T, N) within ``NEAR`` of a joint's range of a limit."""
    margin = NEAR * (upper - lower)
    return np.mean((q <= lower + margin) | (q >= upper - margin), axis=0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--json")
    parser.add_argument("--candidates", type=int, default=40)
    parser.add_argument("--starts", type=int, default=2)
    args = parser.parse_args()
    out = Path(args.out)
    started = time.perf_counter()
    align_stage(
        RECORDING,
        "spade",
        "3d",
        out / "alignment",
        AlignSettings(search=AlignmentConfig(candidates=args.candidates), workers=1),
        progress=False,
    )
    _, world, candidates = load_candidates(out / "alignment")
    rows = [{"alignment_s": round(time.perf_counter() - started, 1), "candidates": len(candidates)}]
    print(json.dumps(rows[0]), flush=True)
    for label, roll, height in VARIANTS:
        started = time.perf_counter()
        robot = build_robot_model(arms.talos(tool_roll=roll), tool_spec("spade"), None, height)
        options = TrajoptSettings(starts=args.starts).track_options()
        selection = select_by_robot_execution(robot, candidates, "spade", world, options, progress=False)
        rewards = selection.robot_rewards
        row: dict = {
            "variant": label,
            "best_spheres": float(np.nanmax(rewards)),
            "earning_candidates": int(np.sum(rewards > 0)),
            "median_spheres": float(np.nanmedian(rewards)),
        }
        if selection.best is not None:
            kept = selection.trajectories[selection.best]
            assert kept is not None
            shares = limit_shares(kept.q, robot.lower, robot.upper)
            row["arm_7_near_limit"] = float(shares[robot.joint_names.index("arm_right_7_joint")])
            if roll:
                row["tool_roll_near_limit"] = float(shares[-1])
                row["tool_roll_range_rad"] = [float(kept.q[:, -1].min()), float(kept.q[:, -1].max())]
            row["median_position_error_m"] = float(np.median(kept.position_error))
        row["wall_time_s"] = round(time.perf_counter() - started, 1)
        print(json.dumps(row), flush=True)
        rows.append(row)
    if args.json:
        Path(args.json).write_text(json.dumps({"settings": vars(args), "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
