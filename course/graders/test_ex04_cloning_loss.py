"""Grader of exercise 04: the cloning loss, checked against the policy's own Gaussian mean.

Each test builds a small SB3 ``ActorCriticPolicy`` and data from a seed, so a failure is
reproducible: the message names the seed and what was expected.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch
from grading import case_seeds, check, fmt
from stable_baselines3.common.policies import ActorCriticPolicy

MODULE = "ex04_cloning_loss"
#: Existing implementations of this exercise: a submission calling one of them gets 0 (grading.py).
#: Points of each test group (all its cases share them): 10 for the exercise.
WEIGHTS = {
    "test_ex04_loss_matches_the_mean_squared_error": 4,
    "test_ex04_loss_is_deterministic": 1,
    "test_ex04_gradient_reaches_the_actor_and_not_the_std": 2,
    "test_ex04_optimising_the_loss_fits_a_linear_expert": 3,
}
#: What each function returns, for the message on a value the checks cannot read.
RETURNS = {"cloning_loss": "a scalar torch tensor (0-d) that requires grad"}
#: Imported in the student's process before their module (it may start no thread afterwards).
STUDENT_IMPORTS = ["numpy", "torch", "stable_baselines3"]
FORBIDDEN = ["toolimit.learn.cloning"]
SEEDS = case_seeds(4)


def make_policy(seed: int, obs_dim: int = 6, act_dim: int = 3) -> ActorCriticPolicy:
    """A small Gaussian policy (net 32-32 tanh) with a deliberately large standard deviation."""
    torch.manual_seed(seed)
    observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(obs_dim,), dtype=np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, shape=(act_dim,), dtype=np.float32)
    return ActorCriticPolicy(observation_space, action_space, lambda _: 1e-3, net_arch=[32, 32], log_std_init=0.5)


def make_data(seed: int, m: int = 64) -> tuple[torch.Tensor, torch.Tensor]:
    generator = torch.Generator().manual_seed(1000 + seed)
    observations = torch.randn(m, 6, generator=generator)
    actions = torch.clamp(0.3 * observations[:, :3] - 0.2 * observations[:, 3:], -1.0, 1.0)
    return observations, actions


def reference(policy: ActorCriticPolicy, observations: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
    return torch.mean((policy.get_distribution(observations).distribution.mean - actions) ** 2)


@pytest.mark.parametrize("seed", SEEDS)
def test_ex04_loss_matches_the_mean_squared_error(submission, seed):
    policy = make_policy(seed)
    observations, actions = make_data(seed)
    got = submission(MODULE).cloning_loss(policy, observations, actions)
    where = f"seed {seed}, {len(observations)} observations of 6 numbers, 3 actions"
    check(
        isinstance(got, torch.Tensor) and got.dim() == 0,
        lambda: (
            f"{where}: expected a scalar tensor, got "
            + (f"a tensor of shape {tuple(got.shape)}" if isinstance(got, torch.Tensor) else f"a {type(got).__name__}")
        ),
    )
    expected = reference(policy, observations, actions)
    check(
        torch.isclose(got.to(expected.dtype), expected, rtol=1e-5),
        f"{where}: expected the MSE of the Gaussian's mean, {fmt(expected, 6)}; got {fmt(got, 6)} "
        "(a sampled action, a sum instead of a mean, or a log-likelihood give other values)",
    )


@pytest.mark.parametrize("seed", SEEDS)
def test_ex04_loss_is_deterministic(submission, seed):
    policy = make_policy(seed)
    observations, actions = make_data(seed)
    first = submission(MODULE).cloning_loss(policy, observations, actions)
    second = submission(MODULE).cloning_loss(policy, observations, actions)
    check(
        isinstance(first, torch.Tensor) and isinstance(second, torch.Tensor),
        lambda: f"seed {seed}: expected a scalar tensor, got {fmt(first)}",
    )
    check(
        torch.equal(first, second),
        lambda: (
            f"seed {seed}: two calls on the same policy and data gave {fmt(first, 6)} and {fmt(second, 6)}: "
            "the loss must use the distribution's mean, not a sampled action"
        ),
    )


def test_ex04_gradient_reaches_the_actor_and_not_the_std(submission):
    policy = make_policy(0)
    observations, actions = make_data(0)
    _, gradients = submission(MODULE).cloning_loss.with_gradients(policy, observations, actions)
    check(gradients, "seed 0: expected a scalar tensor that requires grad (backward() must reach the policy)")
    grad = gradients.get("action_net.weight")
    check(
        isinstance(grad, torch.Tensor) and torch.any(grad != 0),
        "seed 0: after backward() no gradient reaches policy.action_net: is the mean detached?",
    )
    std_grad = gradients.get("log_std")
    check(
        std_grad is None or torch.all(std_grad == 0),
        lambda: (
            f"seed 0: the loss depends on policy.log_std (its gradient is {fmt(std_grad)}): "
            "the standard deviation is set on purpose, never fitted"
        ),
    )


def test_ex04_optimising_the_loss_fits_a_linear_expert(submission):
    policy = make_policy(1)
    observations, actions = make_data(1, m=256)
    optimiser = torch.optim.Adam(policy.parameters(), lr=3e-3)
    start = reference(policy, observations, actions).item()
    parameters = dict(policy.named_parameters())
    for step in range(200):
        optimiser.zero_grad()
        _, gradients = submission(MODULE).cloning_loss.with_gradients(policy, observations, actions)
        check(gradients, f"seed 1, Adam step {step}: expected a scalar tensor that requires grad")
        for name, parameter in parameters.items():
            grad = gradients.get(name)
            parameter.grad = grad.to(parameter.dtype) if isinstance(grad, torch.Tensor) else None
        optimiser.step()
    end = reference(policy, observations, actions).item()
    check(
        end < 0.1 * start,
        f"seed 1, 256 samples: 200 Adam steps (lr 3e-3) on your loss took the mean's squared error from "
        f"{start:.4f} to {end:.4f}; expected below {0.1 * start:.4f}",
    )
