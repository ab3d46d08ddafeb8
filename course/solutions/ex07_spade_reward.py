"""Reference solution of exercise 07 (instructors only)."""

from __future__ import annotations

import numpy as np

CLOSENESS_B = 10.0  # 1/m^2
TOOL_WEIGHT = 0.05


def goal_reward(sand: np.ndarray, box_x: np.ndarray, half_width: float, wall_height: float) -> np.ndarray:
    """(B,) circles strictly inside the goal box."""
    sand = np.asarray(sand, dtype=float)
    inside = (np.abs(sand[..., 0] - np.asarray(box_x, dtype=float)[:, None]) < half_width) & (
        sand[..., 1] < wall_height
    )
    return inside.sum(axis=1).astype(float)


def dense_reward(
    sand: np.ndarray, box_x: np.ndarray, handle_end: np.ndarray | None, deposit_x: float | np.ndarray
) -> np.ndarray:
    """(B,) mean sand closeness to the box's floor centre + 0.05 x the handle's closeness to the deposit."""
    sand = np.asarray(sand, dtype=float)
    box_x = np.asarray(box_x, dtype=float)
    goal = np.stack([box_x, np.zeros_like(box_x)], axis=-1)[:, None, :]
    reward = np.exp(-0.5 * CLOSENESS_B * np.sum((sand - goal) ** 2, axis=-1)).mean(axis=1)
    if handle_end is None:
        return reward
    deposit_x = np.broadcast_to(np.asarray(deposit_x, dtype=float), box_x.shape)
    deposit = np.stack([deposit_x, np.zeros_like(deposit_x)], axis=-1)
    return reward + TOOL_WEIGHT * np.exp(-0.5 * CLOSENESS_B * np.sum((np.asarray(handle_end) - deposit) ** 2, axis=-1))


def episode_success(goal_rewards: np.ndarray, success_count: int = 10) -> np.ndarray:
    """(B,) met on at least half of the steps."""
    met = np.asarray(goal_rewards) >= success_count
    if met.shape[1] == 0:
        return np.zeros(len(met), dtype=bool)
    return met.sum(axis=1) >= 0.5 * met.shape[1]


def first_decisive_step(goal_rewards: np.ndarray, success_count: int = 10) -> np.ndarray:
    """(B,) first t whose steps 0..t already meet the rule for the whole episode, or -1."""
    met = np.asarray(goal_rewards) >= success_count
    if met.shape[1] == 0:
        return np.full(len(met), -1)
    certain = np.cumsum(met, axis=1) >= 0.5 * met.shape[1]
    return np.where(certain.any(axis=1), np.argmax(certain, axis=1), -1).astype(int)
