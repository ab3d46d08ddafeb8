"""Wrong: returns the loss as a Python float (no gradient can flow back to the policy)."""

import torch

CAUGHT_BY = ["test_ex04_loss_matches", "test_ex04_gradient_reaches", "test_ex04_optimising"]


def cloning_loss(policy, observations, expert_actions):
    features = policy.extract_features(observations, policy.pi_features_extractor)
    mean = policy.action_net(policy.mlp_extractor.forward_actor(features))
    return float(torch.mean((mean - expert_actions) ** 2))
