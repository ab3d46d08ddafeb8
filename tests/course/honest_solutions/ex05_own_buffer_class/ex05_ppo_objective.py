"""Honest: GAE written by hand in a class of the student's own whose method borrows SB3's name
(compute_returns_and_advantage): must pass every test, not be refused."""

import numpy as np


class Rollout:
    def __init__(self, rewards, values, episode_starts, gamma, gae_lambda):
        self.rewards, self.values = np.asarray(rewards, float), np.asarray(values, float)
        self.episode_starts = np.asarray(episode_starts, float)
        self.gamma, self.gae_lambda = gamma, gae_lambda

    def compute_returns_and_advantage(self, last_values, dones):
        steps = len(self.rewards)
        advantages = np.zeros_like(self.rewards)
        running = np.zeros(self.rewards.shape[1])
        for t in reversed(range(steps)):
            if t == steps - 1:
                not_done, next_values = 1.0 - np.asarray(dones, float), np.asarray(last_values, float)
            else:
                not_done, next_values = 1.0 - self.episode_starts[t + 1], self.values[t + 1]
            delta = self.rewards[t] + self.gamma * next_values * not_done - self.values[t]
            running = delta + self.gamma * self.gae_lambda * not_done * running
            advantages[t] = running
        return advantages, advantages + self.values


def generalized_advantage_estimation(rewards, values, episode_starts, last_values, dones, gamma, gae_lambda):
    return Rollout(rewards, values, episode_starts, gamma, gae_lambda).compute_returns_and_advantage(last_values, dones)


def clipped_surrogate_loss(log_prob_new, log_prob_old, advantages, clip_range):
    ratio = np.exp(np.asarray(log_prob_new, float) - np.asarray(log_prob_old, float))
    advantages = np.asarray(advantages, float)
    clipped = np.clip(ratio, 1 - clip_range, 1 + clip_range)
    return float(-np.mean(np.minimum(ratio * advantages, clipped * advantages)))
