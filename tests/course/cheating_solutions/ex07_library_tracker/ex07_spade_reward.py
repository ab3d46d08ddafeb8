"""Cheats: the success rule from the scenes' own SuccessTracker (the rest written honestly)."""

import numpy as np

from toolimit.scenes.base import SuccessTracker


def goal_reward(sand, box_x, half_width, wall_height):
    sand = np.asarray(sand, dtype=float)
    inside = (np.abs(sand[..., 0] - np.asarray(box_x)[:, None]) < half_width) & (sand[..., 1] < wall_height)
    return inside.sum(axis=1).astype(float)


def dense_reward(sand, box_x, handle_end, deposit_x):
    return np.zeros(len(box_x))


def episode_success(goal_rewards, success_count=10):
    tracker = SuccessTracker(len(goal_rewards))
    for t in range(np.shape(goal_rewards)[1]):
        tracker.record(np.asarray(goal_rewards)[:, t] >= success_count)
    return tracker.is_success()


def first_decisive_step(goal_rewards, success_count=10):
    return np.full(len(goal_rewards), -1)
