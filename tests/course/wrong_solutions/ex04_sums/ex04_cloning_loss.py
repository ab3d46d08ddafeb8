"""Wrong on purpose: sums the squared errors instead of averaging them."""

import torch

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = ["test_ex04_loss_matches_the_mean_squared_error"]


def cloning_loss(policy, observations, expert_actions):
    mean = policy.get_distribution(observations).distribution.mean
    return torch.sum((mean - expert_actions) ** 2)
