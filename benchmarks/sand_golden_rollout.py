"""Does the Panda spade's sand follow a recorded rollout? Speed work on the kernels must not change the physics.

``benchmarks/results/sand_golden_rollout.npz`` holds two episodes of the shipped 3D spade task (B = 8,
200 spheres, seed 0), recorded on the unchanged kernels: one of the tracking
expert with N(0, 0.2 rad/s) noise (the blade scoops and tips sand, as cloned policies do), and one
of noise alone (the fresh policy of ``benchmarks/learning_throughput.py``: the heap spreads with
no tool contact and then freezes). Per step: the goal rewards and each instance's sum of sphere
centres; at each episode's end every sphere's centre and velocity. The sand is chaotic, so a
change of rounding anywhere in the solver shows within an episode.

The recording is one machine's floating point (numba compiles for the host CPU, which may fuse
multiplies and adds; ``exp`` comes from its libm): on another CPU the sums may differ in their last
bits and grow, which is why this is a benchmark to run on one machine, not a test (the test suite
checks what holds everywhere: one and two threads give the same rollout,
``tests/scenes/test_sand_threads.py``). Before changing the kernels, record from the unchanged ones;
after, compare on the same machine:

    python benchmarks/sand_golden_rollout.py --record   # before
    python benchmarks/sand_golden_rollout.py            # after: the largest deviations, exit 1 beyond 1e-9
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from toolimit.learn import TaskSimulator, shipped_task

GOLDEN = Path(__file__).resolve().parent / "results" / "sand_golden_rollout.npz"
#: Instances, reset seed, and the action noise (rad/s) of the recorded rollout.
BATCH, SEED, NOISE_RAD_S = 8, 0, 0.2
#: Largest difference allowed in a position (m), a velocity (m/s) or a sum of centres (m).
TOLERANCE = 1e-9


def sand_rollout(threads: int = 1) -> dict[str, np.ndarray]:
    """The two recorded episodes, computed now with the instances shared out among ``threads``
    threads (see the module docstring)."""
    simulator = TaskSimulator(shipped_task("spade", "3d"), BATCH, scene_kwargs={"threads": threads})
    reset_rng, action_rng = np.random.default_rng(SEED), np.random.default_rng(SEED + 1)
    noise = NOISE_RAD_S / simulator.robot.velocity_limit
    record: dict[str, np.ndarray] = {}
    for episode in ("tracking", "noise"):
        simulator.reset(reset_rng)
        goals, sums = [], []
        while not simulator.done:
            action = action_rng.normal(0.0, noise, (BATCH, simulator.n_joints))
            if episode == "tracking":
                action = action + simulator.tracking_action()
            _, _, goal = simulator.step(action)
            positions = simulator.scene.sphere_positions
            goals.append(goal)
            sums.append(positions.sum(axis=1))
        record[f"{episode}_goal_rewards"] = np.array(goals)  # (H, B) spheres in the box
        record[f"{episode}_centre_sums"] = np.array(sums)  # (H, B, 3) m
        record[f"{episode}_positions"] = positions  # (B, N, 3) m
        record[f"{episode}_velocities"] = simulator.scene.sphere_velocities  # (B, N, 3) m/s
    return record


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", action="store_true", help="record the rollout (before changing the kernels)")
    parser.add_argument("--threads", type=int, default=1, help="numba threads sharing the instances")
    args = parser.parse_args()
    actual = sand_rollout(args.threads)
    if args.record:
        np.savez_compressed(GOLDEN, **actual)
        print(f"wrote {GOLDEN}", file=sys.stderr)
        return 0
    expected = np.load(GOLDEN)
    worst = 0.0
    for name in expected.files:
        deviation = float(np.max(np.abs(actual[name] - expected[name])))
        worst = max(worst, deviation)
        print(f"{name}: largest deviation {deviation:.3g}")
    print(f"{'same physics' if worst <= TOLERANCE else 'CHANGED'} (tolerance {TOLERANCE:g})")
    return 0 if worst <= TOLERANCE else 1


if __name__ == "__main__":
    sys.exit(main())
