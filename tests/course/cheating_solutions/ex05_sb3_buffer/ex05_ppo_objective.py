"""Cheats on GAE: fills stable-baselines3's RolloutBuffer and calls its compute_returns_and_advantage
(named by a computed string); writes the surrogate by hand."""

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.common import buffers


def generalized_advantage_estimation(rewards, values, episode_starts, last_values, dones, gamma, gae_lambda):
    steps, envs = np.shape(rewards)
    space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
    buffer = buffers.RolloutBuffer(steps, space, space, device="cpu", gamma=gamma, gae_lambda=gae_lambda, n_envs=envs)
    for t in range(steps):
        buffer.add(
            np.zeros((envs, 1)),
            np.zeros((envs, 1)),
            rewards[t],
            episode_starts[t],
            torch.as_tensor(values[t]),
            torch.zeros(envs),
        )
    getattr(buffer, "compute_returns_" + "and_advantage")(torch.as_tensor(last_values), dones)
    return buffer.advantages, buffer.returns


def clipped_surrogate_loss(log_prob_new, log_prob_old, advantages, clip_range):
    ratio = np.exp(np.asarray(log_prob_new, float) - np.asarray(log_prob_old, float))
    advantages = np.asarray(advantages, float)
    clipped = np.clip(ratio, 1 - clip_range, 1 + clip_range)
    return float(-np.mean(np.minimum(ratio * advantages, clipped * advantages)))
