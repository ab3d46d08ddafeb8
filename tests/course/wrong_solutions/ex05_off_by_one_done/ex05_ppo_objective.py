"""Wrong on purpose: uses the episode start of step t instead of t + 1."""

from __future__ import annotations

import numpy as np

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = ["test_ex05_gae_matches_stable_baselines3"]


def generalized_advantage_estimation(rewards, values, episode_starts, last_values, dones, gamma, gae_lambda):
    """Backward recursion of GAE with episode boundaries; returns = advantages + values."""
    rewards, values = np.asarray(rewards, float), np.asarray(values, float)
    advantages = np.zeros_like(rewards)
    running = np.zeros(rewards.shape[1])
    for t in reversed(range(len(rewards))):
        if t == len(rewards) - 1:
            not_done, next_values = 1.0 - np.asarray(dones, float), np.asarray(last_values, float)
        else:
            not_done, next_values = 1.0 - np.asarray(episode_starts[t], float), values[t + 1]
        delta = rewards[t] + gamma * next_values * not_done - values[t]
        running = delta + gamma * gae_lambda * not_done * running
        advantages[t] = running
    return advantages, advantages + values


def clipped_surrogate_loss(log_prob_new, log_prob_old, advantages, clip_range):
    """-mean(min(ratio A, clip(ratio) A))."""
    ratio = np.exp(np.asarray(log_prob_new, float) - np.asarray(log_prob_old, float))
    advantages = np.asarray(advantages, float)
    return float(-np.mean(np.minimum(ratio * advantages, np.clip(ratio, 1 - clip_range, 1 + clip_range) * advantages)))
