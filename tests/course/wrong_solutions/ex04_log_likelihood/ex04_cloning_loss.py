"""Wrong on purpose: the negative log-likelihood, which also fits (and shrinks) the std."""

import torch

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = ["test_ex04_loss_matches_the_mean_squared_error", "test_ex04_gradient_reaches_the_actor_and_not_the_std"]


def cloning_loss(policy, observations, expert_actions):
    _, log_prob, _ = policy.evaluate_actions(observations, expert_actions)
    return -torch.mean(log_prob)
