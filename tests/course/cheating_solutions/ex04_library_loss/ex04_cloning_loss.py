"""Cheats: the library's cloning loss."""

from toolimit.learn.cloning import mean_action_loss


def cloning_loss(policy, observations, expert_actions):
    return mean_action_loss(policy, observations, expert_actions)
