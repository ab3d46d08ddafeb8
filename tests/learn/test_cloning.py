"""Behaviour cloning: tracking-controller data, a loss on the Gaussian's mean, a fixed std, value warm-up."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from toolimit.errors import InputError
from toolimit.learn import BatchedTaskVecEnv
from toolimit.learn.cloning import (
    action_mean,
    clone,
    collect_demonstrations,
    discounted_returns,
    fix_action_std,
    mean_action_loss,
    normalised_action_std,
)
from toolimit.learn.ppo import PRESETS, make_ppo


def test_tracking_controller_rollout_succeeds_and_noisy_rollouts_are_relabelled(spade_task):
    data = collect_demonstrations(spade_task, rollouts=3, action_noise=0.3, seed=0)
    horizon = spade_task.horizon
    assert data.observations.shape == (3 * horizon, 3 + 4 + 3 + 1) and data.actions.shape == (3 * horizon, 3)
    assert data.env_steps == 3 * horizon and bool(data.successes[0])  # the clean rollout is the authors'
    assert np.all(np.abs(data.actions) <= 1.0)
    clean = collect_demonstrations(spade_task, rollouts=1, seed=0)
    np.testing.assert_array_equal(clean.observations, data.observations[:horizon])
    assert not np.allclose(data.observations[horizon:2 * horizon], clean.observations)  # other states visited


def test_discounted_returns():
    rewards = np.array([[1.0], [0.0], [2.0]])
    np.testing.assert_allclose(discounted_returns(rewards, 0.5)[:, 0], [1.5, 1.0, 2.0])


def _model(task):
    return make_ppo(BatchedTaskVecEnv(task, 2, seed=0), PRESETS["authors"], seed=0)


def test_loss_fits_the_mean_not_a_sample_and_leaves_the_std_alone(spade_task):
    model = _model(spade_task)
    policy = model.policy
    observations = torch.randn(16, policy.observation_space.shape[0])
    targets = torch.zeros(16, 3)
    loss = mean_action_loss(policy, observations, targets)
    assert torch.isclose(loss, torch.mean(policy.get_distribution(observations).distribution.mean ** 2))
    assert torch.isclose(loss, mean_action_loss(policy, observations, targets))  # deterministic: no sampling
    loss.backward()
    assert policy.action_net.weight.grad is not None and policy.log_std.grad is None


def test_std_is_the_authors_fixed_value(spade_task):
    model = _model(spade_task)
    std = torch.exp(model.policy.log_std).detach().numpy()
    np.testing.assert_allclose(std, 0.2 / model.get_env().simulator.robot.velocity_limit, rtol=1e-6)
    assert not model.policy.log_std.requires_grad
    fix_action_std(model.policy, np.full(3, 0.5))
    np.testing.assert_allclose(torch.exp(model.policy.log_std).detach().numpy(), 0.5, rtol=1e-6)
    np.testing.assert_allclose(normalised_action_std(np.array([2.0, 4.0])), [0.1, 0.05])
    np.testing.assert_allclose(normalised_action_std(np.array([2.0, 4.0]), 0.05), [0.025, 0.0125])


def test_std_can_be_set_in_rad_per_s(spade_task):
    env = BatchedTaskVecEnv(spade_task, 2, seed=0)
    model = make_ppo(env, PRESETS["authors"], seed=0, action_std=0.05)
    std = torch.exp(model.policy.log_std).detach().numpy()
    np.testing.assert_allclose(std, 0.05 / env.simulator.robot.velocity_limit, rtol=1e-6)


def test_cloning_reduces_both_losses_and_keeps_the_std(spade_task):
    model = _model(spade_task)
    data = collect_demonstrations(spade_task, rollouts=1, seed=0)
    std_before = model.policy.log_std.detach().clone()
    report = clone(model.policy, data, steps=150, value_steps=150, learning_rate=1e-3, progress=False)
    assert report.action_loss_end < 0.2 * report.action_loss_start
    assert report.value_loss_end < 0.5 * report.value_loss_start
    assert torch.equal(model.policy.log_std.detach(), std_before)
    mean = action_mean(model.policy, torch.as_tensor(data.observations)).detach().numpy()
    assert np.isclose(np.mean((mean - data.actions) ** 2), report.action_loss_end, rtol=1e-4)


@pytest.mark.parametrize(
    ("argument", "value", "said"),
    [
        ("steps", -1, "steps must be >= 0, got -1"),
        ("value_steps", -5, "value_steps must be >= 0, got -5"),
        ("batch_size", 0, "batch_size must be >= 1, got 0"),
        ("learning_rate", 0.0, "learning_rate must be positive, got 0.0"),
    ],
)
def test_clone_refuses_a_budget_it_cannot_run(spade_task, argument, value, said):
    model = _model(spade_task)
    data = collect_demonstrations(spade_task, rollouts=1, seed=0)
    before = torch.cat([p.detach().flatten() for p in model.policy.parameters()])
    with pytest.raises(InputError, match=f"^{said}$"):
        clone(model.policy, data, **{argument: value}, progress=False)
    assert torch.equal(torch.cat([p.detach().flatten() for p in model.policy.parameters()]), before)


def test_on_loss_receives_every_steps_loss(spade_task):
    model = _model(spade_task)
    data = collect_demonstrations(spade_task, rollouts=1, seed=0)
    seen = []
    report = clone(model.policy, data, steps=5, value_steps=3, progress=False,
                   on_loss=lambda phase, step, loss: seen.append((phase, step, loss)))
    assert [(phase, step) for phase, step, _ in seen] == [("cloning", k) for k in range(5)] + [
        ("value warm-up", k) for k in range(3)
    ]
    # one rollout fits in a batch: the first step's loss is the whole data's loss before cloning
    assert np.isclose(seen[0][2], report.action_loss_start)
    assert np.isclose(seen[5][2], report.value_loss_start)
