"""The batched VecEnv: SB3's interface, episodes ending together, seeding, the same physics as the Env."""

from __future__ import annotations

import numpy as np
from stable_baselines3.common.env_checker import check_env  # noqa: F401  (the Env is checked in test_env)

from toolimit.learn import BatchedTaskVecEnv


def test_episodes_end_together_with_sb3_infos(spade_task):
    env = BatchedTaskVecEnv(spade_task, 3, seed=0)
    observation = env.reset()
    assert observation.shape == (3, env.simulator.observation_size) and observation.dtype == np.float32
    for t in range(1, spade_task.horizon + 1):
        observation, reward, done, infos = env.step(env.tracking_action())
        assert done.shape == (3,) and bool(done.all()) == (t == spade_task.horizon)
    assert all(info["is_success"] for info in infos)
    assert all(info["episode"]["l"] == spade_task.horizon and not info["TimeLimit.truncated"] for info in infos)
    end_time = spade_task.horizon * spade_task.control_dt  # the observed time is in seconds
    assert all(np.isclose(info["terminal_observation"][-1], end_time) for info in infos)
    assert np.all(observation[:, -1] == 0.0)  # already reset
    assert env.simulation_time_s > 0


def test_seed_makes_resets_repeatable(spade_task):
    env = BatchedTaskVecEnv(spade_task, 2, seed=0)
    env.seed(7)
    first = env.reset()
    env.seed(7)
    np.testing.assert_array_equal(env.reset(), first)
    assert not np.array_equal(env.reset(), first)


def test_restored_rng_state_repeats_the_reset(spade_task):
    env = BatchedTaskVecEnv(spade_task, 2, seed=0)
    env.reset()
    state = env.rng_state_at_reset
    first = env.reset()
    env.restore_rng_state(env.rng_state_at_reset)
    np.testing.assert_array_equal(env.reset(), first)
    env.restore_rng_state(state)
    assert not np.array_equal(env.reset(), first)


def test_get_attr_and_env_method_follow_sb3(spade_task):
    env = BatchedTaskVecEnv(spade_task, 4, seed=0)
    assert env.get_attr("render_mode") == [None] * 4
    assert env.env_is_wrapped(object) == [False] * 4
    assert len(env.env_method("tracking_action", indices=[0, 1])) == 2
