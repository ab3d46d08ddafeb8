"""The Talos's stage-iii selection on the authors' real spade recording: with and without the
authors' tool-roll joint, at their height (pelvis 0.3 m above the scene) and at the former knee
height (0.619 m).

Aligns the recording once (the 3D spade scene, ``--candidates`` K, seed 0), then tracks every
candidate with each Talos variant and replays it in its scene (10 replays): prints the best robot
replay's spheres, how many candidates earn, and the share of the kept trajectory's steps at which
the wrist (arm joint 7) and the tool roll stand within 5 % of their range of a limit.

    python benchmarks/talos_selection.py --out runs/talos --json benchmarks/results/talos_selection.json
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
from toolimit.robots.model import RobotModel, build_robot_model
from toolimit.tools import tool_spec
from toolimit.trajopt import TrajectoryResult
from toolimit.trajopt.selection import AlignedCandidate, load_candidates, select_by_robot_execution

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


def aligned_recording(recording: Path, out: Path, candidates: int) -> tuple[str, list[AlignedCandidate], dict]:
    """Align ``recording`` once in the 3D spade scene (``candidates`` K, seed 0) into out/alignment:
    the world, the candidates and the first row of the printout (the alignment's time)."""
    started = time.perf_counter()
    align_stage(
        recording,
        "spade",
        "3d",
        out / "alignment",
        AlignSettings(search=AlignmentConfig(candidates=candidates), workers=1),
        progress=False,
    )
    _, world, aligned = load_candidates(out / "alignment")
    return world, aligned, {"alignment_s": round(time.perf_counter() - started, 1), "candidates": len(aligned)}


def selection_row(
    robot: RobotModel, candidates: list[AlignedCandidate], world: str, starts: int
) -> tuple[dict, TrajectoryResult | None]:
    """Stage iii's selection by ``robot`` over ``candidates``: its row (the best robot replay's
    spheres, the earning candidates, the median over candidates; the kept trajectory's median
    position error) and the kept trajectory (None if no candidate earns)."""
    options = TrajoptSettings(starts=starts).track_options()
    selection = select_by_robot_execution(robot, candidates, "spade", world, options, progress=False)
    rewards = selection.robot_rewards
    row: dict = {
        "best_spheres": float(np.nanmax(rewards)),
        "earning_candidates": int(np.sum(rewards > 0)),
        "median_spheres": float(np.nanmedian(rewards)),
    }
    kept = None if selection.best is None else selection.trajectories[selection.best]
    if kept is not None:
        row["kept_candidate"] = int(selection.best)  # type: ignore[arg-type]
        row["median_position_error_m"] = float(np.median(kept.position_error))
    return row, kept


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--json")
    parser.add_argument("--candidates", type=int, default=40)
    parser.add_argument("--starts", type=int, default=2)
    args = parser.parse_args()
    world, candidates, first = aligned_recording(RECORDING, Path(args.out), args.candidates)
    rows = [first]
    print(json.dumps(first), flush=True)
    for label, roll, height in VARIANTS:
        started = time.perf_counter()
        robot = build_robot_model(arms.talos(tool_roll=roll), tool_spec("spade"), None, height)
        selected, kept = selection_row(robot, candidates, world, args.starts)
        row: dict = {"variant": label, **selected}
        if kept is not None:
            shares = limit_shares(kept.q, robot.lower, robot.upper)
            row["arm_7_near_limit"] = float(shares[robot.joint_names.index("arm_right_7_joint")])
            if roll:
                row["tool_roll_near_limit"] = float(shares[-1])
                row["tool_roll_range_rad"] = [float(kept.q[:, -1].min()), float(kept.q[:, -1].max())]
        row["wall_time_s"] = round(time.perf_counter() - started, 1)
        print(json.dumps(row), flush=True)
        rows.append(row)
    if args.json:
        Path(args.json).write_text(json.dumps({"settings": vars(args), "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
