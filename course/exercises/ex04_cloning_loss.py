"""Exercise 04: the behaviour-cloning loss on PPO's own policy (stage iv of the method).

Check your work with ``python grade.py check --exercise ex04`` in the course folder (in the
project's repository: ``python course/grade.py check --exercise ex04``); see README.md. Write the
function yourself: a submission that calls an existing implementation of it (toolimit's, a
dependency's, the course's) scores 0 for the exercise.
"""

from __future__ import annotations

import torch
from stable_baselines3.common.policies import ActorCriticPolicy


def cloning_loss(policy: ActorCriticPolicy, observations: torch.Tensor, expert_actions: torch.Tensor) -> torch.Tensor:
    """Return the behaviour-cloning loss: the mean squared error between the *mean* of the
    policy's Gaussian for ``observations`` and ``expert_actions``.

    stable-baselines3 has no pretraining, so cloning trains the ``ActorCriticPolicy`` that PPO will
    fine-tune by ordinary supervised learning. Its action distribution is a Gaussian whose mean
    comes from the actor network and whose standard deviation is a separate parameter
    (``policy.log_std``). Two traps:

    * ``policy(obs)`` *samples* an action from that Gaussian: fitting a sample fits noise.
    * the standard deviation is set on purpose (the paper's authors fixed it at 0.2 rad/s; a learned
      one collapsed), so the loss must not depend on ``policy.log_std``.

    Hints: ``ActorCriticPolicy`` has a method that gives the action distribution for a batch of
    observations, and SB3's ``DiagGaussianDistribution`` wraps a ``torch.distributions.Normal``
    (``help(ActorCriticPolicy)`` or their source tell you more). The loss must let gradients reach
    the actor network and none reach ``policy.log_std``; ``torch.nn.functional`` has the usual losses.

    Args:
        policy: an SB3 ``ActorCriticPolicy`` with a Gaussian (``DiagGaussianDistribution``) head.
        observations: (M, D) float32 tensor of observations.
        expert_actions: (M, N) float32 tensor of the expert's actions, normalised to [-1, 1]
            (joint velocities as fractions of each joint's velocity limit).

    Returns:
        A scalar tensor: the squared error averaged over the M samples and the N action dimensions,
        differentiable with respect to the actor's parameters.
    """
    raise NotImplementedError("exercise 04: the cloning loss on the policy's mean")
