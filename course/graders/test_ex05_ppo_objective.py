"""Grader of exercise 05: GAE against stable-baselines3's own RolloutBuffer, and the clipped
surrogate against the lines of SB3's PPO, on seeded random rollouts with episode boundaries."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch
from stable_baselines3.common.buffers import RolloutBuffer

MODULE = "ex05_ppo_objective"
SEEDS = range(6)


def random_rollout(seed: int, steps: int = 12, envs: int = 3) -> dict:
    rng = np.random.default_rng(seed)
    starts = (rng.random((steps, envs)) < 0.2).astype(np.float32)
    starts[0] = 1.0
    return {"rewards": rng.normal(size=(steps, envs)).astype(np.float32),
            "values": rng.normal(size=(steps, envs)).astype(np.float32),
            "episode_starts": starts, "last_values": rng.normal(size=envs).astype(np.float32),
            "dones": (rng.random(envs) < 0.5).astype(np.float32),
            "gamma": float(rng.uniform(0.9, 1.0)), "gae_lambda": float(rng.uniform(0.5, 1.0))}


def sb3_gae(rollout: dict) -> tuple[np.ndarray, np.ndarray]:
    """SB3's RolloutBuffer filled with the rollout, then compute_returns_and_advantage."""
    steps, envs = rollout["rewards"].shape
    space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
    buffer = RolloutBuffer(steps, space, space, device="cpu", gamma=rollout["gamma"],
                           gae_lambda=rollout["gae_lambda"], n_envs=envs)
    for t in range(steps):
        buffer.add(np.zeros((envs, 1)), np.zeros((envs, 1)), rollout["rewards"][t], rollout["episode_starts"][t],
                   torch.as_tensor(rollout["values"][t]), torch.zeros(envs))
    buffer.compute_returns_and_advantage(torch.as_tensor(rollout["last_values"]), rollout["dones"])
    return buffer.advantages, buffer.returns


@pytest.mark.parametrize("seed", SEEDS)
def test_ex05_gae_matches_stable_baselines3(submission, seed):
    rollout = random_rollout(seed)
    advantages, returns = submission(MODULE).generalized_advantage_estimation(**rollout)
    expected_advantages, expected_returns = sb3_gae(rollout)
    assert np.shape(advantages) == expected_advantages.shape, f"seed {seed}: advantages shape {np.shape(advantages)}"
    bad = np.argwhere(~np.isclose(advantages, expected_advantages, atol=1e-4))
    assert bad.size == 0, (f"seed {seed}: advantage at (t, env) = {tuple(bad[0])} is {advantages[tuple(bad[0])]:.5f}, "
                           f"SB3 gives {expected_advantages[tuple(bad[0])]:.5f} (episode starts there: "
                           f"{rollout['episode_starts'][:, bad[0][1]].astype(int).tolist()})")
    assert np.allclose(returns, expected_returns, atol=1e-4), f"seed {seed}: returns must be advantages + values"


def test_ex05_gae_special_cases(submission):
    rollout = random_rollout(0)
    rollout["episode_starts"][:] = 0.0
    rollout["dones"][:] = 0.0
    one_step, _ = submission(MODULE).generalized_advantage_estimation(**{**rollout, "gae_lambda": 0.0})
    next_values = np.vstack([rollout["values"][1:], rollout["last_values"]])
    td = rollout["rewards"] + rollout["gamma"] * next_values - rollout["values"]
    assert np.allclose(one_step, td, atol=1e-5), "with lambda = 0 the advantages are the one-step TD errors"
    rollout["dones"][:] = 1.0
    monte_carlo, returns = submission(MODULE).generalized_advantage_estimation(**{**rollout, "gamma": 1.0,
                                                                                  "gae_lambda": 1.0})
    expected = np.cumsum(rollout["rewards"][::-1], axis=0)[::-1]
    assert np.allclose(returns, expected, atol=1e-4), "with gamma = lambda = 1 the returns are the rewards to go"


def sb3_policy_loss(new: np.ndarray, old: np.ndarray, advantages: np.ndarray, clip_range: float) -> float:
    """The lines of stable_baselines3/ppo/ppo.py that make the policy loss."""
    ratio = torch.exp(torch.as_tensor(new) - torch.as_tensor(old))
    advantages = torch.as_tensor(advantages)
    policy_loss_1 = advantages * ratio
    policy_loss_2 = advantages * torch.clamp(ratio, 1 - clip_range, 1 + clip_range)
    return float(-torch.min(policy_loss_1, policy_loss_2).mean())


@pytest.mark.parametrize("seed", SEEDS)
def test_ex05_surrogate_matches_stable_baselines3(submission, seed):
    rng = np.random.default_rng(100 + seed)
    old = rng.normal(size=50)
    new = old + rng.normal(scale=0.5, size=50)
    advantages = rng.normal(size=50)
    clip_range = float(rng.choice([0.05, 0.1, 0.2]))
    got = float(submission(MODULE).clipped_surrogate_loss(new, old, advantages, clip_range))
    expected = sb3_policy_loss(new, old, advantages, clip_range)
    assert np.isclose(got, expected, atol=1e-6), (
        f"seed {seed} (clip {clip_range}): expected {expected:.6f}, got {got:.6f}")


def test_ex05_surrogate_hand_case(submission):
    """ratio 2 with A = +1 is clipped to 1.2; ratio 0.5 with A = +1 is not (the min keeps 0.5)."""
    got = float(submission(MODULE).clipped_surrogate_loss(np.log([2.0, 0.5]), np.zeros(2), np.ones(2), 0.2))
    assert np.isclose(got, -(1.2 + 0.5) / 2), f"expected {-(1.2 + 0.5) / 2:.4f}, got {got:.4f}"
