"""Tool-alone and robot replay rewards of the timed tools' demonstrations (hammer, scythe).

For each demonstration: stage ii (alignment, a quick budget) then stage iii (every candidate
tracked by the robot and replayed in its scene). Prints, per demonstration, the best candidate's
alignment reward (``tool_alone``: mean goal reward of its replays of the whole aligned motion), the
best robot replay reward (``robot``), and for the kept candidate its episode's tool-alone reward
and both success rates (:func:`success_rates`), and writes them as JSON. The bar: both > 0 on all five demonstrations of each tool.
For every candidate it also says how its first reward came (:func:`first_reward_motion`): the
head's speed and the roll's turn over that control step.

    python benchmarks/timed_tools_replay.py --out runs/timed --json benchmarks/results/timed_tools_replay.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from toolimit.align.config import AlignmentConfig
from toolimit.align.search import AlignmentResult
from toolimit.errors import StageFoundNothing
from toolimit.pipeline.settings import AlignSettings, TrajoptSettings
from toolimit.pipeline.stages import TrajectoryStage, align_stage, trajopt_stage
from toolimit.robots import make_robot
from toolimit.scenes.registry import make_scene
from toolimit.scenes.replay import replay
from toolimit.tools import ToolPose
from toolimit.trajopt.execution import resample_joints

DEMOS = [f"data/demos/{tool}_{i:02d}.npz" for tool in ("hammer", "scythe") for i in range(5)]


def measure(demo: str, out: Path, config: AlignmentConfig, starts: int, robot: str) -> dict:
    """One demonstration's tool-alone and robot replay rewards (None where a stage found nothing)."""
    tool = Path(demo).stem.split("_")[0]  # hammer_00, scythe_03, hammer_video1_aligned
    started = time.perf_counter()
    row: dict = {"demo": demo, "tool_alone": None, "robot": None}
    try:
        result = align_stage(
            demo,
            tool,
            "3d",
            out / "alignment",
            AlignSettings(search=config, workers=1),
            progress=False,
        )
    except StageFoundNothing:
        row["wall_time_s"] = round(time.perf_counter() - started, 1)
        return row
    assert result.best is not None
    row["tool_alone"] = result.best.reward
    row["candidates"] = len(result.candidates)
    row["samples_tried"] = result.samples_tried
    row |= first_reward_motion(result)
    try:
        stage = trajopt_stage(
            out / "alignment", robot, out / "trajectory", TrajoptSettings(starts=starts, workers=1), progress=False
        )
        selection = stage.selection
        assert selection is not None
        row["robot"] = float(np.nanmax(selection.robot_rewards))
        row["horizon_steps"] = int(len(stage.trajectory.q) - 1)
        row |= success_rates(stage, robot, tool)
    except StageFoundNothing:
        row["robot"] = 0.0
    row["wall_time_s"] = round(time.perf_counter() - started, 1)
    return row


def first_reward_motion(result: AlignmentResult) -> dict:
    """Per candidate (in order): the frame of its first reward, the head's speed over the control
    step that earned it (m/s) and the roll's turn over that step (rad, wrapped to [0, pi]). The
    roll is constant between keypoints and jumps at them; a reward earned with the head nearly
    still and the roll turning came from the blade spun about the snath in one step, not from
    the demonstrated motion."""
    frames, speeds, turns = [], [], []
    for candidate in result.candidates:
        assert candidate.cut is not None  # a timed tool's candidate is always cut
        t = candidate.cut.first_reward_frame
        _, roll, poses = result.aligned_motion(candidate)
        before = max(t - 1, 0)
        frames.append(t)
        speeds.append(round(float(np.linalg.norm(poses.position[t] - poses.position[before]) * result.demo.fps), 3))
        turns.append(round(float(abs(np.angle(np.exp(1j * (roll[t] - roll[before]))))), 3))
    return {"first_reward_frames": frames, "first_reward_head_speed": speeds, "first_reward_roll_turn": turns}


def success_rates(stage: TrajectoryStage, robot: str, tool: str, replays: int = 10) -> dict:
    """The kept candidate's episode (the poses stage iii tracked): its length, the goal reward of its
    tool-alone replays, and the scene's success rate (its own test, e.g. the goal within the first
    second) of those replays and of the kept trajectory's robot replays."""
    trajectory = stage.trajectory
    assert trajectory.scene is not None
    k = trajectory.scene.candidate
    candidate = stage.candidates[k]
    scene = make_scene(tool, "3d")
    targets = candidate.targets
    episode = ToolPose(targets.positions, targets.rotations)
    tool_reward = float(np.mean(replay(scene, candidate.params, np.random.default_rng(k), episode, replays)))
    tool_success = float(np.mean(scene.is_success()))
    model = make_robot(robot, tool=tool)
    q = resample_joints(trajectory.q, trajectory.dt, scene.control_dt)
    positions, rotations = model.tool_poses(q, trajectory.base)
    replay(scene, candidate.params, np.random.default_rng(k), ToolPose(positions, rotations), replays)
    return {
        "kept": k,
        "episode_frames": len(targets.positions),
        "tool_alone_episode": tool_reward,
        "tool_alone_success": tool_success,
        "robot_success": float(np.mean(scene.is_success())),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="work folder")
    parser.add_argument("--json", help="write the rows here")
    parser.add_argument("--samples", type=int, default=3000)
    parser.add_argument("--candidates", type=int, default=5)
    parser.add_argument("--starts", type=int, default=2)
    parser.add_argument("--z-offset-std", type=float, default=AlignmentConfig.z_offset_std)
    parser.add_argument("--robot", default="panda")
    parser.add_argument("--demos", nargs="*", default=DEMOS)
    args = parser.parse_args()
    rows = []
    for demo in args.demos:
        config = AlignmentConfig(samples=args.samples, candidates=args.candidates, z_offset_std=args.z_offset_std)
        row = measure(demo, Path(args.out) / Path(demo).stem, config, args.starts, args.robot)
        print(json.dumps(row), flush=True)
        rows.append(row)
    if args.json:
        Path(args.json).write_text(json.dumps({"settings": vars(args), "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
