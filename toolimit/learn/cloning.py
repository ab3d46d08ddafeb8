"""Behaviour cloning on PPO's own policy: SB3 has no pretraining, so the ``ActorCriticPolicy`` that
PPO will fine-tune is trained here by supervised learning on the tracking controller's actions.

Data (the authors'): one rollout of the tracking controller along the optimised trajectory
(:meth:`TaskSimulator.tracking_action`), observation -> action. Optionally more rollouts in which
the executed action is perturbed by Gaussian noise while the recorded label stays the controller's
action at the state actually reached (relabelling, as in DART): the data then cover the states a
noisy policy visits, not only the reference's.

Fit: the mean of the policy's Gaussian (MSE), never a sampled action (``policy(obs)`` draws one).
The standard deviation is set, not fitted: :func:`fix_action_std` freezes it at the authors' 0.2
rad/s (a learned one collapsed in their runs). The value network is warmed up on the rollouts'
discounted returns so that PPO's first advantages are not those of an untrained critic.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import torch
from stable_baselines3.common.policies import ActorCriticPolicy

from toolimit.errors import InputError
from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.task import LearningTask
from toolimit.progress import progress_bar

#: The authors' fixed standard deviation of the joint velocities, rad/s.
AUTHORS_ACTION_STD = 0.2


@dataclass(frozen=True)
class Demonstrations:
    """State-action pairs of tracking-controller rollouts.

    Attributes:
        observations: (M, D) float32 observations (see :mod:`toolimit.learn.simulator`).
        actions: (M, N) float32 controller actions in [-1, 1] (fractions of the action scale).
        returns: (M,) float32 discounted return from each state to the episode's end.
        goal_rewards: (E,) final goal reward of each rollout; successes: (E,) bool.
        env_steps: environment steps simulated (M).
    """

    observations: np.ndarray
    actions: np.ndarray
    returns: np.ndarray
    goal_rewards: np.ndarray
    successes: np.ndarray
    env_steps: int


def collect_demonstrations(
    task: LearningTask,
    rollouts: int = 1,
    action_noise: float = 0.0,
    gamma: float = 0.999,
    seed: int = 0,
    scene_kwargs: dict[str, Any] | None = None,
    reward: str = "sparse",
    adr: bool = False,
) -> Demonstrations:
    """Roll the tracking controller out ``rollouts`` times at once (one batched scene).

    Rollout 0 executes the controller's actions exactly (the authors' data); the others execute them
    plus N(0, ``action_noise``) (normalised units) and record the controller's action at each state
    reached. ``gamma`` discounts the returns of the value warm-up, which are those of ``reward``
    (the reward PPO will learn with, :data:`toolimit.learn.simulator.REWARDS`). ``adr``: the
    observations hold the goal box position, which stays at the aligned one (the ADR bounds' start).
    """
    if rollouts < 1 or not action_noise >= 0.0:
        raise ValueError(f"need rollouts >= 1 and action_noise >= 0, got {rollouts} and {action_noise}")
    rng = np.random.default_rng(seed)
    simulator = TaskSimulator(task, batch_size=rollouts, scene_kwargs=scene_kwargs, reward=reward, adr=adr)
    observation = simulator.reset(rng)
    noise_scale = np.full((rollouts, 1), action_noise)
    noise_scale[0] = 0.0
    observations, actions, rewards = [], [], []
    while not simulator.done:
        action = simulator.tracking_action()
        observations.append(observation)
        actions.append(action)
        executed = action + noise_scale * rng.normal(size=action.shape)
        observation, step_reward, goal = simulator.step(executed)
        rewards.append(step_reward)
    returns = discounted_returns(np.array(rewards), gamma)
    return Demonstrations(
        observations=np.concatenate(np.swapaxes(np.array(observations), 0, 1)).astype(np.float32),
        actions=np.concatenate(np.swapaxes(np.array(actions), 0, 1)).astype(np.float32),
        returns=np.concatenate(returns.T).astype(np.float32),
        goal_rewards=goal,
        successes=simulator.is_success(),
        env_steps=rollouts * simulator.t,
    )


def discounted_returns(rewards: np.ndarray, gamma: float) -> np.ndarray:
    """(T, B) returns G_t = r_t + gamma G_{t+1} of rewards (T, B), with G_T = 0."""
    returns = np.zeros_like(rewards, dtype=float)
    running = np.zeros(rewards.shape[1])
    for t in range(len(rewards) - 1, -1, -1):
        running = rewards[t] + gamma * running
        returns[t] = running
    return returns


def action_mean(policy: ActorCriticPolicy, observations: torch.Tensor) -> torch.Tensor:
    """(M, N) the mean of the policy's Gaussian for observations (M, D)."""
    features = cast(torch.Tensor, policy.extract_features(observations, policy.pi_features_extractor))
    return policy.action_net(policy.mlp_extractor.forward_actor(features))


def mean_action_loss(policy: ActorCriticPolicy, observations: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
    """Mean squared error between the policy's action mean and the demonstrated actions."""
    return torch.mean((action_mean(policy, observations) - actions) ** 2)


def fix_action_std(policy: ActorCriticPolicy, std: np.ndarray) -> None:
    """Set the policy's standard deviation to ``std`` (N,) (normalised action units) and freeze it."""
    with torch.no_grad():
        policy.log_std.copy_(torch.as_tensor(np.log(std), dtype=policy.log_std.dtype))
    policy.log_std.requires_grad_(False)


def normalised_action_std(action_scale: np.ndarray, std: float = AUTHORS_ACTION_STD) -> np.ndarray:
    """(N,) a joint-velocity standard deviation ``std`` (rad/s; the authors' 0.2 by default) as a
    fraction of each joint's action scale (rad/s, ``TaskSimulator.action_scale``), the policy's
    action units."""
    return std / np.asarray(action_scale, dtype=float)


@dataclass(frozen=True)
class CloningReport:
    """Losses of :func:`clone`: action MSE (normalised units^2) and value MSE, first and last step."""

    action_loss_start: float
    action_loss_end: float
    value_loss_start: float
    value_loss_end: float


def clone(
    policy: ActorCriticPolicy,
    demonstrations: Demonstrations,
    steps: int = 6000,
    learning_rate: float = 1e-4,
    value_steps: int = 2000,
    batch_size: int = 512,
    seed: int = 0,
    progress: bool = True,
    on_loss: Callable[[str, int, float], None] | None = None,
) -> CloningReport:
    """Fit the policy's action mean to the demonstrations (Adam, the authors' 6,000 steps at 1e-4),
    then warm the value network up on their returns (``value_steps``, same optimiser settings).

    Each step uses the whole data set when it holds at most ``batch_size`` pairs (the authors'
    full batch: one rollout of a few hundred steps), else ``batch_size`` pairs drawn at random
    (seeded by ``seed``), so that more rollouts do not make a step dearer. The standard deviation
    is left as it is (see :func:`fix_action_std`).

    ``on_loss(phase, step, loss)``, if given, receives every step's training loss (on that step's
    rows, before the step): phase ``"cloning"`` (action MSE, normalised units^2) then
    ``"value warm-up"`` (value MSE); the learning curves.
    """
    for name, value, lowest in (("steps", steps, 0), ("value_steps", value_steps, 0), ("batch_size", batch_size, 1)):
        if value < lowest:
            raise InputError(f"{name} must be >= {lowest}, got {value!r}")
    if not learning_rate > 0:
        raise InputError(f"learning_rate must be positive, got {learning_rate!r}")
    observations = torch.as_tensor(demonstrations.observations, device=policy.device)
    actions = torch.as_tensor(demonstrations.actions, device=policy.device)
    returns = torch.as_tensor(demonstrations.returns, device=policy.device)
    actor = [*policy.mlp_extractor.policy_net.parameters(), *policy.action_net.parameters()]
    critic = [*policy.mlp_extractor.value_net.parameters(), *policy.value_net.parameters()]
    generator = torch.Generator().manual_seed(seed)

    def action_loss(rows: torch.Tensor | slice) -> torch.Tensor:
        return mean_action_loss(policy, observations[rows], actions[rows])

    def value_loss(rows: torch.Tensor | slice) -> torch.Tensor:
        return torch.mean((policy.predict_values(observations[rows]).flatten() - returns[rows]) ** 2)

    size = len(observations)
    action_losses = _fit(
        actor, action_loss, size, batch_size, steps, learning_rate, generator, progress, "cloning", on_loss
    )
    value_losses = _fit(
        critic, value_loss, size, batch_size, value_steps, learning_rate, generator, progress, "value warm-up", on_loss
    )
    return CloningReport(action_losses[0], action_losses[-1], value_losses[0], value_losses[-1])


def _fit(
    parameters: list[torch.nn.Parameter],
    loss_of: Callable[[torch.Tensor | slice], torch.Tensor],
    size: int,
    batch_size: int,
    steps: int,
    learning_rate: float,
    generator: torch.Generator,
    progress: bool,
    description: str,
    on_loss: Callable[[str, int, float], None] | None = None,
) -> list[float]:
    """Minimise ``loss_of(rows)`` over ``parameters`` for ``steps`` Adam steps on minibatches of
    ``batch_size`` of ``size`` rows (all rows if fewer); the whole-data loss before and after.
    ``on_loss(description, step, loss)`` receives each step's minibatch loss."""
    optimiser = torch.optim.Adam(parameters, lr=learning_rate)
    everything = slice(None)
    with torch.no_grad():
        losses = [float(loss_of(everything))]
    for step in progress_bar(range(steps), desc=description, unit="step", disable=not progress, leave=False):
        rows = everything if size <= batch_size else torch.randint(size, (batch_size,), generator=generator)
        optimiser.zero_grad()
        loss = loss_of(rows)
        if on_loss is not None:
            on_loss(description, step, float(loss.detach()))
        loss.backward()
        optimiser.step()
    with torch.no_grad():
        losses.append(float(loss_of(everything)))
    return losses
