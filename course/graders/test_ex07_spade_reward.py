"""Grader of exercise 07: the planar spade's goal reward, dense shaping and success rule, checked
against the scene's own definitions (``toolimit.scenes``: its box test, ``dense_spade_reward``,
``SuccessTracker``) on seeded sand clouds and reward sequences. Each function is a part of its own.
"""

from __future__ import annotations

import numpy as np
import pytest
from grading import case_seeds, check, fail, fmt, fmt_shape

from toolimit.scenes.base import SuccessTracker, dense_spade_reward

MODULE = "ex07_spade_reward"
#: Points of each test group (all its cases share them): 10 for the exercise.
WEIGHTS = {
    "test_ex07_goal_reward_counts_the_circles_in_the_box": 2.5,
    "test_ex07_goal_reward_boundaries_are_outside": 1,
    "test_ex07_dense_reward_matches_the_shaping": 2.5,
    "test_ex07_dense_reward_before_the_spade_is_placed": 0.5,
    "test_ex07_success_rule": 2,
    "test_ex07_first_decisive_step": 1.5,
}
#: What each function returns, for the message on a value the checks cannot read.
RETURNS = {
    "goal_reward": "a (B,) float array, circles in the box",
    "dense_reward": "a (B,) float array in [0, 1.05]",
    "episode_success": "a (B,) bool array",
    "first_decisive_step": "a (B,) int array, a step index or -1",
}
#: Imported in the student's process before their module (it may start no thread afterwards).
STUDENT_IMPORTS = ["numpy"]
#: The scene's own rewards and success rule: a submission calling them gets 0 (grading.py).
FORBIDDEN = [
    "toolimit.scenes.planar.spade",
    "toolimit.scenes.spatial.spade",
    "toolimit.scenes.base.dense_spade_reward",
    "toolimit.scenes.base.gaussian_closeness",
    "toolimit.scenes.base.SuccessTracker",
]
#: The planar spade's goal box (the scene's defaults, ``goal_half_width`` and ``goal_wall_height``), m.
HALF_WIDTH = 0.175
WALL_HEIGHT = 0.10


def sand_cloud(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(B, N, 2) circle centres, a third of them around the box, and (B,) box centres, m."""
    rng = np.random.default_rng(seed)
    batch, circles = int(rng.integers(1, 6)), int(rng.integers(5, 80))
    box_x = rng.uniform(-0.5, 0.5, size=batch)
    sand = np.stack([rng.uniform(-1.0, 1.0, (batch, circles)), rng.uniform(0.0, 0.3, (batch, circles))], axis=-1)
    near = rng.random((batch, circles)) < 0.35
    sand[..., 0] = np.where(near, box_x[:, None] + rng.uniform(-0.25, 0.25, (batch, circles)), sand[..., 0])
    return sand, box_x


def reference_goal_reward(sand: np.ndarray, box_x: np.ndarray) -> np.ndarray:
    """The scene's box test (``PlanarSpadeScene._in_goal_box``)."""
    inside = (np.abs(sand[..., 0] - box_x[:, None]) < HALF_WIDTH) & (sand[..., 1] < WALL_HEIGHT)
    return inside.sum(axis=1).astype(float)


def as_batch(got, batch: int, where: str, kind: str = "float") -> np.ndarray:
    """The student's (B,) answer as an array, or one failure naming what was expected."""
    try:
        array = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        fail(f"{where}: expected a ({batch},) {kind} array, got {fmt(got)}")
    check(array.shape == (batch,), f"{where}: expected shape ({batch},), got {fmt_shape(got)}")
    check(np.all(np.isfinite(array)), f"{where}: expected finite values, got {fmt(array)}")
    return array


@pytest.mark.parametrize("seed", case_seeds(6))
def test_ex07_goal_reward_counts_the_circles_in_the_box(submission, seed):
    sand, box_x = sand_cloud(seed)
    expected = reference_goal_reward(sand, box_x)
    where = f"seed {seed}, {sand.shape[0]} instances of {sand.shape[1]} circles, boxes at x = {fmt(box_x, 3)} m"
    got = as_batch(
        submission(MODULE).goal_reward(sand.copy(), box_x.copy(), HALF_WIDTH, WALL_HEIGHT), len(box_x), where
    )
    check(np.array_equal(got, expected), f"{where}: expected {fmt(expected)} circles in the box, got {fmt(got)}")


def test_ex07_goal_reward_boundaries_are_outside(submission):
    box_x = np.array([0.2])
    sand = np.array(
        [[[0.2, 0.05], [0.2 + HALF_WIDTH, 0.05], [0.2 - HALF_WIDTH, 0.05], [0.2, WALL_HEIGHT], [0.3, -0.01]]]
    )
    got = as_batch(submission(MODULE).goal_reward(sand, box_x, HALF_WIDTH, WALL_HEIGHT), 1, "hand case")
    check(
        got[0] == 2.0,
        f"box at x = 0.2 m, half-width {HALF_WIDTH} m, walls {WALL_HEIGHT} m: circles at {fmt(sand[0])}: two are in "
        f"the box (one at its centre, one below the ground line); on a wall or at the walls' top is outside "
        f"(strict inequalities); got {fmt(got[0])}",
    )


@pytest.mark.parametrize("seed", case_seeds(6, 20))
def test_ex07_dense_reward_matches_the_shaping(submission, seed):
    sand, box_x = sand_cloud(seed)
    rng = np.random.default_rng([seed, 1])
    handle = np.stack([rng.uniform(-1, 1, len(box_x)), rng.uniform(0.0, 0.8, len(box_x))], axis=-1)
    deposit_x = rng.uniform(-1.0, 0.0, len(box_x))
    goal = np.stack([box_x, np.zeros_like(box_x)], axis=-1)[:, None, :]
    deposit = np.stack([deposit_x, np.zeros_like(deposit_x)], axis=-1)
    expected = dense_spade_reward(sand, goal, handle, deposit)
    where = f"seed {seed}, {sand.shape[0]} instances of {sand.shape[1]} circles"
    got = as_batch(
        submission(MODULE).dense_reward(sand.copy(), box_x.copy(), handle.copy(), deposit_x.copy()), len(box_x), where
    )
    sand_only = dense_spade_reward(sand, goal, None, deposit)
    check(
        np.allclose(got, expected, rtol=1e-9, atol=1e-12),
        f"{where}: expected {fmt(expected, 6)} (of which the sand term {fmt(sand_only, 6)}), got {fmt(got, 6)}: "
        "the mean (not the sum) over circles of exp(-5 d^2), plus 0.05 exp(-5 d^2) for the handle end",
    )


def test_ex07_dense_reward_before_the_spade_is_placed(submission):
    sand, box_x = sand_cloud(3)
    goal = np.stack([box_x, np.zeros_like(box_x)], axis=-1)[:, None, :]
    expected = dense_spade_reward(sand, goal, None, np.zeros(2))
    got = as_batch(submission(MODULE).dense_reward(sand, box_x, None, 0.0), len(box_x), "handle_end None")
    check(
        np.allclose(got, expected, rtol=1e-9, atol=1e-12),
        f"handle_end None (before the first step): expected the sand term alone {fmt(expected, 6)}, got {fmt(got, 6)}",
    )


def success_cases(seed: int) -> np.ndarray:
    """(B, T) goal rewards near the boundary of the rule: met on about half of the steps."""
    rng = np.random.default_rng(seed)
    steps = int(rng.integers(1, 40))
    batch = 12
    met = rng.random((batch, steps)) < rng.uniform(0.3, 0.7, (batch, 1))
    met[0] = np.arange(steps) < (steps + 1) // 2  # exactly the half (rounded up)
    met[1] = np.arange(steps) < steps // 2  # rounded down: one short when steps is odd
    return np.where(met, rng.integers(10, 25, met.shape), rng.integers(0, 10, met.shape)).astype(float)


def reference_success(rewards: np.ndarray) -> np.ndarray:
    tracker = SuccessTracker(len(rewards))
    for t in range(rewards.shape[1]):
        tracker.record(rewards[:, t] >= 10)
    return tracker.is_success()


@pytest.mark.parametrize("seed", case_seeds(6, 40))
def test_ex07_success_rule(submission, seed):
    rewards = success_cases(seed)
    expected = reference_success(rewards)
    where = f"seed {seed}, {rewards.shape[0]} episodes of {rewards.shape[1]} steps, success_count 10"
    got = as_batch(submission(MODULE).episode_success(rewards.copy(), 10), len(rewards), where, "bool")
    wrong = np.flatnonzero(got.astype(bool) != expected)
    if wrong.size:
        b = int(wrong[0])
        met = int(np.sum(rewards[b] >= 10))
        fail(
            f"{where}: episode {b} meets the goal on {met} of {rewards.shape[1]} steps (half is "
            f"{rewards.shape[1] / 2:g}): expected {bool(expected[b])}, got {bool(got[b])}"
        )


@pytest.mark.parametrize("seed", case_seeds(4, 60))
def test_ex07_first_decisive_step(submission, seed):
    rewards = success_cases(seed)
    met = rewards >= 10
    certain = np.cumsum(met, axis=1) >= 0.5 * met.shape[1]
    expected = np.where(certain.any(axis=1), np.argmax(certain, axis=1), -1)
    where = f"seed {seed}, {rewards.shape[0]} episodes of {rewards.shape[1]} steps"
    got = as_batch(submission(MODULE).first_decisive_step(rewards.copy(), 10), len(rewards), where, "int")
    wrong = np.flatnonzero(got != expected)
    if wrong.size:
        b = int(wrong[0])
        fail(
            f"{where}: episode {b}, goal met at steps {np.flatnonzero(met[b]).tolist()}: its success is certain "
            f"from step {int(expected[b])} on (-1: never), got {fmt(got[b])}"
        )
