"""Wrong: the surrogate's minus sign forgotten: the update makes the sampled good actions less likely."""

from __future__ import annotations

import numpy as np
import torch

CAUGHT_BY = ["test_ex09_one_update_improves_the_surrogate", "test_ex09_learns_to_reach_the_goal"]


def ppo_update(
    policy,
    observations,
    actions,
    old_log_probs,
    advantages,
    returns,
    clip_range=0.2,
    learning_rate=3e-3,
    epochs=4,
    minibatch_size=64,
    seed=0,
):
    """Minibatch Adam epochs on the clipped surrogate + 0.5 x the value loss; the new parameters."""
    generator = np.random.default_rng(seed)
    optimiser = torch.optim.Adam(policy.parameters(), lr=learning_rate)
    obs = torch.as_tensor(observations, dtype=torch.float32)
    act = torch.as_tensor(actions, dtype=torch.float32)
    old, adv, ret = (torch.as_tensor(a, dtype=torch.float32) for a in (old_log_probs, advantages, returns))
    for _ in range(epochs):
        order = generator.permutation(len(obs))
        for start in range(0, len(obs), minibatch_size):
            index = torch.as_tensor(order[start : start + minibatch_size])
            values, log_prob, _ = policy.evaluate_actions(obs[index], act[index])
            normalised = (adv[index] - adv[index].mean()) / (adv[index].std() + 1e-8)
            ratio = torch.exp(log_prob - old[index])
            clipped = torch.clamp(ratio, 1 - clip_range, 1 + clip_range)
            surrogate = torch.mean(torch.min(ratio * normalised, clipped * normalised))
            loss = surrogate + 0.5 * torch.mean((values.flatten() - ret[index]) ** 2)
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
    return {name: value.detach().numpy().copy() for name, value in policy.state_dict().items()}
