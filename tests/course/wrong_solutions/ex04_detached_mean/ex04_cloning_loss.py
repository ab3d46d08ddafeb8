"""Wrong on purpose: the right value, but the mean is detached, so nothing is learned."""

import torch

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = ["test_ex04_gradient_reaches_the_actor_and_not_the_std", "test_ex04_optimising_the_loss"]


def cloning_loss(policy, observations, expert_actions):
    mean = policy.get_distribution(observations).distribution.mean.detach()
    return torch.mean((mean - expert_actions) ** 2).requires_grad_()
