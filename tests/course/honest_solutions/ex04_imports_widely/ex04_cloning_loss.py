"""Honest: writes the loss itself but imports widely (toolimit.learn.ppo, which imports the forbidden
toolimit.learn.cloning, and torch's MSE): must pass every test, not be refused."""

import torch
import torch.nn.functional as F

import toolimit.learn  # noqa: F401 - imported for its side effects only
from toolimit.learn.ppo import PRESETS  # noqa: F401


def cloning_loss(policy, observations, expert_actions):
    distribution = policy.get_distribution(observations)
    mean = distribution.distribution.mean
    return F.mse_loss(mean, expert_actions.to(torch.float32))
