"""Reference solution of exercise 04 (instructors): MSE on the Gaussian's mean."""

from __future__ import annotations

import torch
from stable_baselines3.common.policies import ActorCriticPolicy


def cloning_loss(policy: ActorCriticPolicy, observations: torch.Tensor, expert_actions: torch.Tensor) -> torch.Tensor:
    """Mean over samples and dimensions of (mean action - expert action)^2."""
    features = policy.extract_features(observations, policy.pi_features_extractor)
    mean = policy.action_net(policy.mlp_extractor.forward_actor(features))
    return torch.mean((mean - expert_actions) ** 2)
