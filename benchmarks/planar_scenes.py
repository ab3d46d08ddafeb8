"""Speed of the planar scenes: one alignment sample = reset(batch_size=10) + one pass of a motion.

Alignment replays each sampled scene 10 times over ~100 frames and tries thousands of samples, so
the spade target is one 10-replay sample of ~100 frames well under 0.5 s. Prints, per scene and
motion, the mean CPU time (process time, robust on a shared machine) and wall time of a sample and
the mean goal reward.

Motions: a scripted one per tool (scoop / strike / sweep), and, when ../shared/data/video_demos is
present, the authors' real spade demonstration projected onto the x-z plane (a hand-picked scene
where it earns reward; it digs through the whole pile, the expensive case).

    python benchmarks/planar_scenes.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from toolimit.scenes import make_scene
from toolimit.tools import ToolPose, tool_poses

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("TOOLIMIT_SHARED", REPO.parent / "shared")) / "data" / "video_demos"
FPS = 24.0


def spade_scoop() -> ToolPose:
    """100 frames: slide under the pile at x = 0, carry, tip into a box at x = 0.8 m, hold."""
    keys = np.array([(0, -0.5, 0.10, 5), (0.4, -0.32, 0.035, 0), (1.2, 0.12, 0.035, 0), (1.6, 0.15, 0.25, -12),
                     (2.4, 0.65, 0.30, -12), (3.0, 0.72, 0.25, 50), (99 / FPS, 0.72, 0.25, 60)])
    t = np.arange(100) / FPS
    x, z, angle = (np.interp(t, keys[:, 0], keys[:, i]) for i in (1, 2, 3))
    head = np.stack([x, np.zeros_like(x), z], 1)
    angle = np.radians(angle)
    return tool_poses(head, head + 0.4 * np.stack([-np.cos(angle), np.zeros_like(angle), np.sin(angle)], 1))


def hammer_strikes() -> ToolPose:
    """100 frames: four strikes at 3 m/s, each ending 2 cm deeper, on a nail whose top is at z = 0.3 m."""
    top = 0.3 + 0.055  # head centre when the face touches the nail top
    z = np.concatenate([
        np.concatenate([bottom + 0.125 * np.arange(3, -1, -1), np.linspace(bottom, top + 0.375, 21)])
        for bottom in top - 0.02 * np.arange(1, 5)
    ])
    head = np.stack([np.full(100, 0.5), np.zeros(100), z], 1)
    return tool_poses(head, head + np.array([0.33, 0.0, 0.0]))


def scythe_sweeps() -> ToolPose:
    """100 frames: the blade swept back and forth through the patch at 2 m/s, 5 cm high."""
    x = 0.6 + 0.4 * np.sin(2 * np.pi * np.arange(100) / 50)
    head = np.stack([x, np.full(100, 0.5 - 0.225), np.full(100, 0.05)], 1)
    return tool_poses(head, head + np.array([0.0, 0.0, 1.0]), roll=np.pi / 2)


def real_spade() -> tuple[ToolPose, dict] | None:
    path = SHARED / "spade_video1_aligned.npz"
    if not path.is_file():
        return None
    from toolimit.demos import load_demo

    demo = load_demo(path).projected_to_plane("xz")
    poses = tool_poses(demo.head + [0, 0, 0.03], demo.handle + [0, 0, 0.03], roll=np.pi)
    return poses, {"sand_position": np.array([-0.75, 0, 0]), "goal_position": np.array([0.0, 0, 0])}


def time_sample(tool: str, params: dict, poses: ToolPose, repeats: int) -> tuple[float, float, float]:
    """Mean CPU s, wall s and goal reward of reset(batch_size=10) + stepping through ``poses``."""
    scene = make_scene(tool, "planar")
    cpu, wall, reward = [], [], []
    for seed in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        scene.reset(params, np.random.default_rng(seed), batch_size=10)
        for position, rotation in zip(poses.position, poses.rotation):
            scene.step(ToolPose(position, rotation))
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
        reward.append(scene.goal_reward().mean())
    return float(np.mean(cpu)), float(np.mean(wall)), float(np.mean(reward))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    runs = [
        ("spade", "scripted scoop", {"sand_position": np.zeros(3), "goal_position": np.array([0.8, 0, 0])},
         spade_scoop()),
        ("hammer", "scripted strikes", {"nail_position": np.array([0.5, 0.0, 0.3])}, hammer_strikes()),
        ("scythe", "scripted sweeps", {"grass_position": np.array([0.6, 0.5, 0.0])}, scythe_sweeps()),
    ]
    real = real_spade()
    if real is not None:
        runs.append(("spade", "real video 1 (xz)", real[1], real[0]))
    print(f"{'scene':8s} {'motion':20s} {'frames':>6s} {'cpu s':>7s} {'wall s':>7s} {'reward':>7s}   (B = 10)")
    for tool, name, params, poses in runs:
        cpu, wall, reward = time_sample(tool, params, poses, args.repeats)
        print(f"{tool:8s} {name:20s} {len(poses.position):6d} {cpu:7.3f} {wall:7.3f} {reward:7.2f}")


if __name__ == "__main__":
    main()
