"""Wrong on purpose: fits the action ``policy(obs)`` samples instead of the Gaussian's mean."""

import torch

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = ["test_ex04_loss_matches_the_mean_squared_error", "test_ex04_loss_is_deterministic"]


def cloning_loss(policy, observations, expert_actions):
    actions, _, _ = policy(observations)
    return torch.mean((actions - expert_actions) ** 2)
