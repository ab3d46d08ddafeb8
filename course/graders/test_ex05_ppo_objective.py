"""Grader of exercise 05: GAE against stable-baselines3's own RolloutBuffer, and the clipped
surrogate against the lines of SB3's PPO, on seeded random rollouts with episode boundaries."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch
from grading import case_seeds, check, fmt, fmt_shape
from stable_baselines3.common.buffers import RolloutBuffer

MODULE = "ex05_ppo_objective"
#: Existing implementations of this exercise: a submission calling one of them gets 0 (grading.py).
#: SB3's buffer computes GAE; its PPO.train computes the surrogate.
#: Points of each test group (all its cases share them): 10 for the exercise.
WEIGHTS = {
    "test_ex05_gae_matches_stable_baselines3": 4,
    "test_ex05_gae_special_cases": 2,
    "test_ex05_surrogate_matches_stable_baselines3": 3,
    "test_ex05_surrogate_hand_case": 1,
}
#: What each function returns, for the message on a value the checks cannot read.
RETURNS = {
    "generalized_advantage_estimation": "a tuple (advantages, returns) of two arrays shaped like rewards",
    "clipped_surrogate_loss": "a scalar (a 0-d tensor or a float), the loss to minimise",
}
#: Imported in the student's process before their module (it may start no thread afterwards).
STUDENT_IMPORTS = ["numpy", "torch", "stable_baselines3"]
FORBIDDEN = [
    "stable_baselines3.common.buffers.RolloutBuffer.compute_returns_and_advantage",
    "stable_baselines3.common.buffers.DictRolloutBuffer.compute_returns_and_advantage",
    "stable_baselines3.ppo.ppo.PPO.train",
]
SEEDS = case_seeds(6)


def random_rollout(seed: int, steps: int = 12, envs: int = 3) -> dict:
    rng = np.random.default_rng(seed)
    starts = (rng.random((steps, envs)) < 0.2).astype(np.float32)
    starts[0] = 1.0
    return {
        "rewards": rng.normal(size=(steps, envs)).astype(np.float32),
        "values": rng.normal(size=(steps, envs)).astype(np.float32),
        "episode_starts": starts,
        "last_values": rng.normal(size=envs).astype(np.float32),
        "dones": (rng.random(envs) < 0.5).astype(np.float32),
        "gamma": float(rng.uniform(0.9, 1.0)),
        "gae_lambda": float(rng.uniform(0.5, 1.0)),
    }


def sb3_gae(rollout: dict) -> tuple[np.ndarray, np.ndarray]:
    """SB3's RolloutBuffer filled with the rollout, then compute_returns_and_advantage."""
    steps, envs = rollout["rewards"].shape
    space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
    buffer = RolloutBuffer(
        steps, space, space, device="cpu", gamma=rollout["gamma"], gae_lambda=rollout["gae_lambda"], n_envs=envs
    )
    for t in range(steps):
        buffer.add(
            np.zeros((envs, 1)),
            np.zeros((envs, 1)),
            rollout["rewards"][t],
            rollout["episode_starts"][t],
            torch.as_tensor(rollout["values"][t]),
            torch.zeros(envs),
        )
    buffer.compute_returns_and_advantage(torch.as_tensor(rollout["last_values"]), rollout["dones"])
    return buffer.advantages, buffer.returns


def first_wrong_step(got: np.ndarray, expected: np.ndarray, atol: float) -> tuple[int, int] | None:
    """(t, env) of the first wrong value in the order of the backward recursion: t = T-1 first,
    then T-2, ...; within a step, the first environment. None when all agree."""
    wrong = ~np.isclose(got, expected, atol=atol)
    for t in reversed(range(len(expected))):
        envs = np.flatnonzero(wrong[t])
        if envs.size:
            return t, int(envs[0])
    return None


def describe_step(rollout: dict, t: int, env: int) -> str:
    """The inputs of step t of the recursion for one environment, in plain numbers."""
    steps = len(rollout["rewards"])
    if t == steps - 1:
        next_value, done, done_name = rollout["last_values"][env], rollout["dones"][env], "dones[env]"
    else:
        next_value, done, done_name = (
            rollout["values"][t + 1, env],
            rollout["episode_starts"][t + 1, env],
            (f"episode_starts[{t + 1}, env]"),
        )
    return (
        f"r_t = {fmt(rollout['rewards'][t, env])}, V(s_t) = {fmt(rollout['values'][t, env])}, "
        f"V(s_t+1) = {fmt(next_value)}, done after step t ({done_name}) = {fmt(done)}, "
        f"gamma = {fmt(rollout['gamma'])}, lambda = {fmt(rollout['gae_lambda'])}"
    )


@pytest.mark.parametrize("seed", SEEDS)
def test_ex05_gae_matches_stable_baselines3(submission, seed):
    rollout = random_rollout(seed)
    steps, envs = rollout["rewards"].shape
    answer = submission(MODULE).generalized_advantage_estimation(
        **{key: np.copy(value) if isinstance(value, np.ndarray) else value for key, value in rollout.items()}
    )
    check(
        isinstance(answer, tuple) and len(answer) == 2,
        f"seed {seed}: expected a pair (advantages, returns), got {fmt_shape(answer)}",
    )
    advantages, returns = (np.asarray(part, dtype=float) for part in answer)
    expected_advantages, expected_returns = sb3_gae(rollout)
    where = f"seed {seed} (T = {steps} steps, E = {envs} environments)"
    check(
        advantages.shape == expected_advantages.shape,
        f"{where}: expected advantages of shape {expected_advantages.shape}, got {advantages.shape}",
    )
    wrong = first_wrong_step(advantages, expected_advantages, 1e-4)
    if wrong is not None:
        t, env = wrong
        check(
            False,
            f"{where}: going backwards from t = T-1 = {steps - 1}, the first wrong advantage is at "
            f"t = {t}, env {env}: expected A_t = {fmt(expected_advantages[t, env])}, "
            f"got {fmt(advantages[t, env])}; at that step {describe_step(rollout, t, env)}"
            + ("" if t == steps - 1 else f", A_t+1 = {fmt(expected_advantages[t + 1, env])}"),
        )
    check(
        returns.shape == expected_returns.shape,
        f"{where}: expected returns of shape {expected_returns.shape}, got {returns.shape}",
    )
    wrong = first_wrong_step(returns, expected_returns, 1e-4)
    if wrong is not None:
        t, env = wrong
        check(
            False,
            f"{where}: returns must be advantages + values; at t = {t}, env {env}: expected "
            f"{fmt(expected_returns[t, env])} = {fmt(expected_advantages[t, env])} + "
            f"{fmt(rollout['values'][t, env])}, got {fmt(returns[t, env])}",
        )


def test_ex05_gae_special_cases(submission):
    rollout = random_rollout(0)
    rollout["episode_starts"][:] = 0.0
    rollout["dones"][:] = 0.0
    one_step, _ = submission(MODULE).generalized_advantage_estimation(**{**rollout, "gae_lambda": 0.0})
    next_values = np.vstack([rollout["values"][1:], rollout["last_values"]])
    td = rollout["rewards"] + rollout["gamma"] * next_values - rollout["values"]
    wrong = first_wrong_step(np.asarray(one_step, dtype=float), td, 1e-5)
    check(
        wrong is None,
        lambda: (
            f"seed 0, no episode boundary, lambda = 0: the advantages are the one-step TD "
            f"errors; at t = {wrong[0]}, env {wrong[1]} expected {fmt(td[wrong])}, "
            f"got {fmt(np.asarray(one_step)[wrong])}"
        ),
    )
    rollout["dones"][:] = 1.0
    monte_carlo, returns = submission(MODULE).generalized_advantage_estimation(
        **{**rollout, "gamma": 1.0, "gae_lambda": 1.0}
    )
    expected = np.cumsum(rollout["rewards"][::-1], axis=0)[::-1]
    wrong = first_wrong_step(np.asarray(returns, dtype=float), expected, 1e-4)
    check(
        wrong is None,
        lambda: (
            f"seed 0, gamma = lambda = 1, every last step done: the returns are the rewards to "
            f"go; at t = {wrong[0]}, env {wrong[1]} expected {fmt(expected[wrong])}, "
            f"got {fmt(np.asarray(returns)[wrong])}"
        ),
    )


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
    answer = submission(MODULE).clipped_surrogate_loss(new, old, advantages, clip_range)
    check(np.size(answer) == 1, f"seed {100 + seed}: expected one number, got {fmt_shape(answer)}")
    got = float(np.asarray(answer, dtype=float).ravel()[0])
    expected = sb3_policy_loss(new, old, advantages, clip_range)
    check(
        np.isclose(got, expected, atol=1e-6),
        f"seed {100 + seed}: 50 samples, clip_range {clip_range}: expected the loss {expected:.6f}, got {got:.6f}",
    )


def test_ex05_surrogate_hand_case(submission):
    """ratio 2 with A = +1 is clipped to 1.2; ratio 0.5 with A = +1 is not (the min keeps 0.5)."""
    answer = submission(MODULE).clipped_surrogate_loss(np.log([2.0, 0.5]), np.zeros(2), np.ones(2), 0.2)
    check(np.size(answer) == 1, f"expected one number, got {fmt_shape(answer)}")
    got = float(np.asarray(answer, dtype=float).ravel()[0])
    check(
        np.isclose(got, -(1.2 + 0.5) / 2),
        f"ratios 2 and 0.5, advantages 1 and 1, clip_range 0.2: expected {-(1.2 + 0.5) / 2:.4f} "
        f"(-(1.2 + 0.5) / 2), got {got:.4f}",
    )
