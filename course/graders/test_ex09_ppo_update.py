"""Grader of exercise 09: one PPO update, graded by what it does (not by equality): on a 1-D
"reach the goal" task the grader rolls the policy out, computes GAE, and calls the student's update.

Parts: every parameter comes back; one update lowers the clipped surrogate on its own batch and
keeps the policy close (the ratio); the value network fits the returns; 24 updates reach the goal
in at least 80 % of 64 episodes (the reference solution: 100 % on seeds 0 to 7).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch
from grading import case_seeds, check, fail, fmt
from stable_baselines3.common.policies import ActorCriticPolicy

MODULE = "ex09_ppo_update"
#: Points of each test group (all its cases share them): 10 for the exercise.
WEIGHTS = {
    "test_ex09_returns_every_parameter": 1,
    "test_ex09_one_update_improves_the_surrogate": 3,
    "test_ex09_value_fits_the_returns": 2,
    "test_ex09_learns_to_reach_the_goal": 4,
}
#: What each function returns, for the message on a value the checks cannot read.
RETURNS = {"ppo_update": "a dict {parameter name: array} of every entry of policy.state_dict()"}
#: Imported in the student's process before their module (it may start no thread afterwards).
STUDENT_IMPORTS = ["numpy", "torch", "stable_baselines3"]
#: PPO's training in stable-baselines3 and the library's learning: 0 points if called (grading.py).
FORBIDDEN = ["stable_baselines3.ppo", "toolimit.learn"]
ENVS, STEPS, UPDATES = 16, 20, 24  # episodes per update, steps per episode, updates
SUCCESS_DISTANCE = 0.1  # m from the goal at the episode's end
REQUIRED_SUCCESS = 0.8

torch.set_num_threads(1)  # small networks: one thread is faster, and the student's process has one


def make_policy(seed: int) -> ActorCriticPolicy:
    torch.manual_seed(seed)
    observation_space = gym.spaces.Box(-2.0, 2.0, shape=(2,), dtype=np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
    return ActorCriticPolicy(observation_space, action_space, lambda _: 3e-3, net_arch=[32, 32], log_std_init=-0.5)


def rollout(policy: ActorCriticPolicy, rng: np.random.Generator, envs: int = ENVS, deterministic: bool = False):
    """Episodes of the 1-D task: x and the goal in [-1, 1], x += 0.2 clip(a), reward -|x - goal|.
    Returns the (STEPS, envs, ...) arrays and the (envs,) success at the end."""
    x, goal = rng.uniform(-1, 1, envs), rng.uniform(-1, 1, envs)
    columns: dict[str, list] = {"obs": [], "actions": [], "log_probs": [], "values": [], "rewards": []}
    for _ in range(STEPS):
        observation = torch.as_tensor(np.stack([x, goal], axis=1).astype(np.float32))
        with torch.no_grad():
            distribution = policy.get_distribution(observation)
            action = distribution.mode() if deterministic else distribution.sample()
            log_prob, value = distribution.log_prob(action), policy.predict_values(observation).squeeze(-1)
        x = x + 0.2 * np.clip(action.numpy()[:, 0], -1.0, 1.0)
        for key, item in zip(
            columns, (observation.numpy(), action.numpy(), log_prob.numpy(), value.numpy(), -np.abs(x - goal))
        ):
            columns[key].append(item)
    return {key: np.array(items) for key, items in columns.items()}, np.abs(x - goal) < SUCCESS_DISTANCE


def advantages_of(rewards: np.ndarray, values: np.ndarray, gamma: float = 0.99, lam: float = 0.95):
    advantages, running = np.zeros_like(rewards), np.zeros(rewards.shape[1])
    for t in reversed(range(len(rewards))):
        next_values = values[t + 1] if t + 1 < len(rewards) else 0.0
        running = rewards[t] + gamma * next_values - values[t] + gamma * lam * running
        advantages[t] = running
    return advantages, advantages + values


def batch(policy: ActorCriticPolicy, rng: np.random.Generator) -> dict[str, np.ndarray]:
    data, _ = rollout(policy, rng)
    advantages, returns = advantages_of(data["rewards"], data["values"])
    flat = {key: value.reshape(STEPS * ENVS, *value.shape[2:]) for key, value in data.items()}
    return {**flat, "advantages": advantages.ravel(), "returns": returns.ravel()}


def update(submission, policy: ActorCriticPolicy, data: dict, seed: int, where: str) -> ActorCriticPolicy:
    """The policy with the student's returned parameters loaded, or one failure saying why not."""
    got = submission(MODULE).ppo_update(
        policy,
        data["obs"],
        data["actions"],
        data["log_probs"],
        data["advantages"],
        data["returns"],
        0.2,
        3e-3,
        4,
        64,
        seed,
    )
    check(isinstance(got, dict), lambda: f"{where}: expected a dict {{parameter name: array}}, got {fmt(got)}")
    expected = policy.state_dict()
    missing = sorted(set(expected) - set(got))
    check(not missing, f"{where}: parameters missing from your dict: {', '.join(missing[:5])}")
    loaded = {}
    for name, value in expected.items():
        try:
            array = np.asarray(got[name], dtype=np.float32)
        except (TypeError, ValueError):
            fail(f"{where}: parameter {name}: expected an array of shape {tuple(value.shape)}, got {fmt(got[name])}")
        check(
            array.shape == tuple(value.shape),
            f"{where}: parameter {name}: expected shape {tuple(value.shape)}, got {array.shape}",
        )
        check(np.all(np.isfinite(array)), f"{where}: parameter {name} holds NaN or infinite values")
        loaded[name] = torch.as_tensor(array)
    policy.load_state_dict(loaded)
    return policy


def surrogate_and_ratio(policy: ActorCriticPolicy, data: dict) -> tuple[float, float, float]:
    """(clipped surrogate loss on the batch with normalised advantages, mean |ratio - 1|, value MSE)."""
    with torch.no_grad():
        values, log_prob, _ = policy.evaluate_actions(torch.as_tensor(data["obs"]), torch.as_tensor(data["actions"]))
    advantages = torch.as_tensor(data["advantages"])
    advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
    ratio = torch.exp(log_prob - torch.as_tensor(data["log_probs"]))
    loss = -torch.mean(torch.min(ratio * advantages, torch.clamp(ratio, 0.8, 1.2) * advantages))
    value_error = torch.mean((values.flatten() - torch.as_tensor(data["returns"])) ** 2)
    return float(loss), float(torch.mean(torch.abs(ratio - 1))), float(value_error)


def test_ex09_returns_every_parameter(submission):
    policy = make_policy(0)
    data = batch(policy, np.random.default_rng(0))
    update(submission, make_policy(0), data, 0, "seed 0, one update")


@pytest.mark.parametrize("seed", case_seeds(3, 10))
def test_ex09_one_update_improves_the_surrogate(submission, seed):
    policy = make_policy(seed)
    data = batch(policy, np.random.default_rng(seed))
    before, _, _ = surrogate_and_ratio(policy, data)
    after, drift, _ = surrogate_and_ratio(update(submission, make_policy(seed), data, seed, f"seed {seed}"), data)
    check(
        after < before - 1e-3,
        f"seed {seed}: the clipped surrogate loss on the update's own batch went from {before:.4f} to {after:.4f}: "
        "an update must lower it (is the sign right? do the minibatch steps reach the actor?)",
    )
    check(
        drift < 0.5,
        f"seed {seed}: after the update the probability ratio of the batch's actions is off 1 by {drift:.2f} on average: "
        "the clip keeps each update close to the policy that collected the data",
    )


@pytest.mark.parametrize("seed", case_seeds(3, 20))
def test_ex09_value_fits_the_returns(submission, seed):
    policy = make_policy(seed)
    data = batch(policy, np.random.default_rng(seed))
    _, _, before = surrogate_and_ratio(policy, data)
    _, _, after = surrogate_and_ratio(update(submission, make_policy(seed), data, seed, f"seed {seed}"), data)
    check(
        after < 0.9 * before,
        f"seed {seed}: the value network's squared error on the returns went from {before:.4f} to {after:.4f}; "
        f"expected below {0.9 * before:.4f} (0.5 x the value loss belongs to the minimised loss)",
    )


@pytest.mark.parametrize("seed", case_seeds(2, 30))
def test_ex09_learns_to_reach_the_goal(submission, seed):
    policy, rng = make_policy(seed), np.random.default_rng(seed)
    _, start = rollout(policy, np.random.default_rng([seed, 1]), envs=64, deterministic=True)
    for iteration in range(UPDATES):
        policy = update(submission, policy, batch(policy, rng), iteration, f"seed {seed}, update {iteration}")
    _, success = rollout(policy, np.random.default_rng([seed, 1]), envs=64, deterministic=True)
    check(
        success.mean() >= REQUIRED_SUCCESS,
        f"seed {seed}: after {UPDATES} updates ({UPDATES * ENVS * STEPS} steps) the policy's mean reaches the goal in "
        f"{success.mean():.2f} of 64 episodes (untrained: {start.mean():.2f}); expected at least {REQUIRED_SUCCESS}",
    )
