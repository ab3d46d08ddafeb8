"""The Panda spade's sand follows a recorded rollout: speed work on the kernels must not change the physics.

``tests/scenes/data/sand_golden_rollout.npz`` holds two episodes of the shipped 3D spade task (B = 8,
200 spheres, seed 0), recorded before the sand kernels were made faster: one of the tracking
expert with N(0, 0.2 rad/s) noise (the blade scoops and tips sand, as cloned policies do), and one
of noise alone (the fresh policy of ``benchmarks/learning_throughput.py``: the heap spreads with
no tool contact and then freezes). Per step: the goal rewards and each instance's sum of sphere
centres; at each episode's end every sphere's centre and velocity. The sand is chaotic, so a
change of rounding anywhere in the solver shows within an episode.

The recording is this machine's floating point (numba compiles for the host CPU; ``exp`` comes
from its libm). On another CPU or build the sums may differ in their last bits and grow: then
re-record from the unchanged kernels with ``python tests/scenes/test_sand_golden_rollout.py``
before changing them, and compare after.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from toolimit.learn import TaskSimulator, shipped_task

GOLDEN = Path(__file__).resolve().parent / "data" / "sand_golden_rollout.npz"
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


@pytest.mark.parametrize("threads", [1, 2])
def test_the_spade_sand_follows_the_recorded_rollout(threads: int) -> None:
    expected = np.load(GOLDEN)
    actual = sand_rollout(threads)
    assert sorted(actual) == sorted(expected.files)
    assert actual["tracking_goal_rewards"].max() >= 10, "the recorded scoop delivers sand: the check sees contacts"
    for name in expected.files:
        np.testing.assert_allclose(actual[name], expected[name], rtol=0, atol=TOLERANCE, err_msg=name)


if __name__ == "__main__":  # re-record (see the module docstring)
    GOLDEN.parent.mkdir(exist_ok=True)
    np.savez_compressed(GOLDEN, **sand_rollout())
    print(f"wrote {GOLDEN}", file=sys.stderr)
