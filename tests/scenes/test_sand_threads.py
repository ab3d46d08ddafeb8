"""The sand's kernels shared out among numba's threads compute what one thread computes, bit for bit
(in one run, on one machine: what holds on every CPU; the recorded rollout that kernel speed work is
checked against is ``benchmarks/sand_golden_rollout.py``)."""

from __future__ import annotations

import numpy as np

from toolimit.learn import TaskSimulator, shipped_task


def _noisy_tracking(threads: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Panda spade's tracking expert with N(0, 0.2 rad/s) noise for 60 steps, B = 4: the goal
    rewards (T, B), the spheres' first and final centres (B, N, 3) m."""
    simulator = TaskSimulator(shipped_task("spade", "3d"), 4, scene_kwargs={"threads": threads})
    simulator.reset(np.random.default_rng(0))
    first = simulator.scene.sphere_positions.copy()
    rng = np.random.default_rng(1)
    goals = []
    for _ in range(60):
        noise = rng.normal(0.0, 0.2 / simulator.robot.velocity_limit, (4, simulator.n_joints))
        goals.append(simulator.step(simulator.tracking_action() + noise)[2])
    return np.array(goals), first, simulator.scene.sphere_positions.copy()


def test_two_threads_step_the_sand_as_one_does() -> None:
    one_goals, first, one_positions = _noisy_tracking(threads=1)
    two_goals, _, two_positions = _noisy_tracking(threads=2)
    assert np.abs(one_positions - first).max() > 0.05, "the sand moved: not a frozen heap compared"
    np.testing.assert_array_equal(two_goals, one_goals)
    np.testing.assert_array_equal(two_positions, one_positions)
