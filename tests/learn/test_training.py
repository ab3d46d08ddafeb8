"""learn_policy on a tiny budget: its files, an exact resume, evaluation."""

from __future__ import annotations

import dataclasses
import json
import time

import numba
import numpy as np
import pytest
import torch

from toolimit.errors import InputError, InvalidLearningConfig
from toolimit.learn import BatchedTaskVecEnv, LearningTask, shipped_task, training
from toolimit.learn.evaluate import evaluate
from toolimit.learn.ppo import PRESETS, make_ppo
from toolimit.learn.training import CLONE_CHECK_EPISODES, CURVE_JSONL, LearningConfig, learn_policy, load_policy

TINY = LearningConfig(
    timesteps=0,
    envs=2,
    preset="toolimit",
    clone_rollouts=2,
    clone_noise=0.3,
    clone_steps=20,
    value_steps=20,
    checkpoint_every=1,
    seed=0,
)


def _parameters(model):
    return torch.cat([p.detach().flatten() for p in model.policy.parameters()]).numpy()


def test_files_and_record(spade_task, tmp_path):
    horizon = spade_task.horizon
    config = LearningConfig(**{**TINY.__dict__, "timesteps": 2 * horizon * 2})
    outcome = learn_policy(spade_task, tmp_path, config, progress=False)
    for name in ("task.npz", "cloning.json", "checkpoint.json", "policy.safetensors", "learning.json", CURVE_JSONL):
        assert (tmp_path / name).is_file(), name
    # the last update's model stays the checkpoint; policy.safetensors is the best check's, here (no check
    # in two updates) the last update's (tests/learn/test_early_stop.py: the kept policy)
    assert json.loads((tmp_path / "checkpoint.json").read_text())["model"] == "checkpoint.safetensors"
    record = json.loads((tmp_path / "learning.json").read_text())
    assert record["ppo_env_steps"] == 2 * horizon * 2
    assert record["cloning_env_steps"] == (2 + CLONE_CHECK_EPISODES) * horizon, "the rollouts, then the clone's check"
    assert record["env_steps"] == record["ppo_env_steps"] + record["cloning_env_steps"]
    assert 0 < record["simulation_time_s"] < record["wall_time_s"]
    curve = [json.loads(line) for line in (tmp_path / CURVE_JSONL).read_text().splitlines()]
    assert [c["env_steps"] for c in curve] == [2 * horizon * (k + 1) for k in range(len(curve))]
    assert {"return_mean", "success_rate", "goal_reward_mean", "action_std_mean", "approx_kl"} <= set(curve[0])
    model, task = load_policy(tmp_path)
    np.testing.assert_array_equal(_parameters(model), _parameters(outcome.model))
    assert task.horizon == horizon
    assert record["sim_threads"] is None, "the planar scene takes no threads"


def test_an_interrupted_run_resumes_exactly(spade_task, tmp_path):
    """Three updates in one go, or stopped during the third and run again: same network, and the
    record's times count the first sitting up to its last checkpoint."""
    per_update = spade_task.horizon * 2  # 1 episode per update (toolimit preset) x 2 envs
    three = LearningConfig(**{**TINY.__dict__, "timesteps": 3 * per_update})
    whole = learn_policy(spade_task, tmp_path / "whole", three, progress=False)
    pause_s = 1.0

    def stop(record: dict) -> None:  # called as an update's rollout starts, before its checkpoint
        if record["env_steps"] == per_update:
            time.sleep(pause_s)  # in the first sitting, before the checkpoint the run resumes from
        if record["env_steps"] == 2 * per_update:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        learn_policy(spade_task, tmp_path / "split", three, on_record=stop, progress=False)
    assert (tmp_path / "split" / "checkpoint.safetensors").is_file() and not (tmp_path / "split" / "policy.safetensors").exists()
    started = time.perf_counter()
    resumed = learn_policy(spade_task, tmp_path / "split", three, progress=False)
    second_sitting_s = time.perf_counter() - started
    assert resumed.record["resumed"] and resumed.model.num_timesteps == 3 * per_update
    assert resumed.record["wall_time_s"] > second_sitting_s + pause_s
    assert resumed.record["simulation_time_s"] > 0
    np.testing.assert_allclose(_parameters(resumed.model), _parameters(whole.model), rtol=0, atol=1e-6)
    lines = (tmp_path / "split" / CURVE_JSONL).read_text().splitlines()
    assert len(lines) == 3


def test_a_finished_run_continues_to_a_larger_budget_exactly(spade_task, tmp_path):
    """One update, finished (its final checkpoint is policy.safetensors), then run to three: as in one go."""
    per_update = spade_task.horizon * 2
    three = LearningConfig(**{**TINY.__dict__, "timesteps": 3 * per_update})
    whole = learn_policy(spade_task, tmp_path / "whole", three, progress=False)
    learn_policy(
        spade_task, tmp_path / "split", LearningConfig(**{**TINY.__dict__, "timesteps": per_update}), progress=False
    )
    resumed = learn_policy(spade_task, tmp_path / "split", three, progress=False)
    assert resumed.record["resumed"] and resumed.model.num_timesteps == 3 * per_update
    np.testing.assert_allclose(_parameters(resumed.model), _parameters(whole.model), rtol=0, atol=1e-6)


def test_a_resumed_runs_progress_starts_from_its_earlier_steps(spade_task, tmp_path, monkeypatch):
    """The bar of a resumed run starts at the steps already made, so that tqdm's rate and ETA count
    only this sitting's steps against this sitting's time."""
    per_update = spade_task.horizon * 2
    learn_policy(spade_task, tmp_path, LearningConfig(**{**TINY.__dict__, "timesteps": per_update}), progress=False)
    bars, progress_bar = [], training.progress_bar

    def recording_bar(*args, **kwargs):
        bars.append(progress_bar(*args, **kwargs))
        return bars[-1]

    monkeypatch.setattr(training, "progress_bar", recording_bar)
    learn_policy(spade_task, tmp_path, LearningConfig(**{**TINY.__dict__, "timesteps": 3 * per_update}))
    ppo_bar = next(bar for bar in bars if bar.desc == "PPO")
    assert ppo_bar.format_dict["initial"] == per_update and ppo_bar.n == 3 * per_update
    assert ppo_bar.total == 3 * per_update


def test_evaluation_reports_success_and_joint_trajectories(spade_task, tmp_path):
    outcome = learn_policy(spade_task, tmp_path, TINY, progress=False)
    result = evaluate(outcome.model, spade_task, episodes=3, deterministic=True, seed=1)
    assert result.joint_positions.shape == (3, spade_task.horizon + 1, 3)
    assert result.successes.dtype == bool and result.goal_rewards.shape == (3,)
    record = result.record()
    assert record["episodes"] == 3 and 0.0 <= record["success_rate"] <= 1.0


def test_a_checkpoint_is_not_resumed_with_other_ppo_settings(spade_task, tmp_path):
    """SB3's checkpoint keeps its own settings: a resume with others is refused, and the run's
    files stay as they were (the task file is written again first, the same task)."""
    per_update = spade_task.horizon * 2
    learn_policy(spade_task, tmp_path, LearningConfig(**{**TINY.__dict__, "timesteps": per_update}), progress=False)

    def written() -> dict:
        return {path.name: path.read_bytes() for path in tmp_path.iterdir() if path.name != "task.npz"}

    before = written()
    faster = LearningConfig(**{**TINY.__dict__, "timesteps": 2 * per_update, "learning_rate": 1e-4})
    with pytest.raises(InputError) as refused:
        learn_policy(spade_task, tmp_path, faster, progress=False)
    assert str(refused.value) == (
        f"{tmp_path / 'checkpoint.json'}: this checkpoint was written with other PPO settings "
        "(learning_rate: 0.0003, now 0.0001); give the flags it was written with, or start a new output folder"
    )
    assert written() == before


def test_the_action_limit_is_learnt_kept_with_the_policy_and_not_changed_on_resume(spade_task, tmp_path):
    """The learnt task keeps the action limit, so that the policy is rolled out as it learnt; a
    resume with another limit is refused in one line."""
    per_update = spade_task.horizon * 2
    authors = LearningConfig(**{**TINY.__dict__, "timesteps": per_update, "action_limit": 3.0})
    learn_policy(spade_task, tmp_path, authors, progress=False)
    model, task = load_policy(tmp_path)
    assert task.action_limit == 3.0 and spade_task.action_limit is None
    robot_limits = LearningConfig(**{**TINY.__dict__, "timesteps": 2 * per_update})
    with pytest.raises(InputError) as refused:
        learn_policy(spade_task, tmp_path, robot_limits, progress=False)
    assert str(refused.value) == (
        f"{tmp_path / 'task.npz'}: this checkpoint was learnt with --action-limit 3; "
        "give it again or start a new output folder"
    )
    assert LearningTask.load(tmp_path).action_limit == 3.0, "the refused run leaves the task as it was"


def test_evaluation_refuses_zero_episodes(spade_task):
    model = make_ppo(BatchedTaskVecEnv(spade_task, 2, seed=0), PRESETS["toolimit"], seed=0)
    with pytest.raises(InputError, match="^episodes must be >= 1, got 0$"):
        evaluate(model, spade_task, episodes=0)


def test_unknown_preset_is_refused():
    with pytest.raises(ValueError, match="unknown preset 'fast'"):
        LearningConfig(preset="fast").settings()


def test_the_learning_rate_and_target_kl_given_replace_the_presets():
    assert LearningConfig(preset="toolimit").settings() == PRESETS["toolimit"]
    settings = LearningConfig(preset="toolimit", learning_rate=1e-4, target_kl=0.1).settings()
    assert settings == dataclasses.replace(PRESETS["toolimit"], learning_rate=1e-4, target_kl=0.1)


@pytest.mark.parametrize(("target_kl", "steps_per_update"), [(None, 4), (1e-12, 1)])
def test_target_kl_stops_an_update_after_its_first_minibatch_step(spade_task, tmp_path, target_kl, steps_per_update):
    """The preset's four minibatch steps per update, or with a tiny ``target_kl`` only the first: it
    starts at the rollout's own policy (KL 0), and the second minibatch's KL exceeds the bound."""
    from toolimit.learn.ppo import train

    settings = LearningConfig(preset="toolimit", target_kl=target_kl).settings()
    model = make_ppo(BatchedTaskVecEnv(spade_task, 2, seed=0), settings, seed=0)
    steps = []
    model.policy.optimizer.register_step_post_hook(lambda *_: steps.append(1))
    updates = 2
    train(model, updates * 2 * spade_task.horizon, tmp_path, checkpoint_every=10)
    assert len(steps) == updates * steps_per_update


@pytest.mark.parametrize(
    ("field", "value", "said"),
    [
        ("envs", 0, "envs: must be an integer >= 1, got 0"),
        ("timesteps", -1, "timesteps: must be an integer >= 0, got -1"),
        ("checkpoint_every", 2.5, "checkpoint_every: must be an integer >= 1, got 2.5"),
        ("torch_threads", 0, "torch_threads: must be an integer >= 1, got 0"),
        ("clone_noise", float("nan"), "clone_noise: must be a finite number >= 0, got nan"),
        ("action_std", 0.0, "action_std: must be a finite number > 0 (rad/s), got 0.0"),
        ("action_limit", -3.0, "action_limit: must be a finite number > 0 (rad/s), got -3.0"),
        ("target_kl", 0.0, "target_kl: must be a finite number > 0, got 0.0"),
        ("learning_rate", float("inf"), "learning_rate: must be a finite number > 0, got inf"),
        ("reward", "shaped", "reward: unknown reward 'shaped'; choose one of sparse, dense"),
        (
            "sim_threads",
            0,
            f"sim_threads: must be an integer in 1..{numba.config.NUMBA_NUM_THREADS} (numba's NUMBA_NUM_THREADS), got 0",
        ),
        ("scene_kwargs", {"threads": 2}, "scene_kwargs: give the simulation's threads as sim_threads"),
    ],
)
def test_a_setting_no_run_can_use_is_refused_naming_its_field(field, value, said):
    with pytest.raises(InvalidLearningConfig) as refused:
        LearningConfig(**{field: value})
    assert str(refused.value) == said and refused.value.field == field
    assert isinstance(refused.value, InputError)  # the command line answers it in one line


def test_learned_std_stays_above_the_authors_floor(spade_task, tmp_path):
    """Without cloning the std is learned; after an update it is never below 0.01 rad/s."""
    from toolimit.learn import BatchedTaskVecEnv
    from toolimit.learn.ppo import PRESETS, STD_FLOOR, make_ppo, train

    env = BatchedTaskVecEnv(spade_task, 2, seed=0)
    model = make_ppo(env, PRESETS["toolimit"], seed=0, learn_std=True)
    assert model.policy.log_std.requires_grad
    with torch.no_grad():
        model.policy.log_std.fill_(-20.0)
    train(model, 2 * 2 * spade_task.horizon, tmp_path, checkpoint_every=10)
    std = torch.exp(model.policy.log_std).detach().numpy() * env.simulator.robot.velocity_limit
    assert np.all(std >= STD_FLOOR * (1 - 1e-5)), std


@pytest.mark.parametrize(
    ("cores", "numba_threads", "processes", "envs", "threads"),
    [
        (2, 2, 1, 16, 2),  # a two-core laptop: both cores
        (8, 8, 2, 16, 4),  # shared among the processes
        (8, 3, 1, 16, 3),  # NUMBA_NUM_THREADS lowered (reproduce --jobs)
        (8, 8, 1, 2, 2),  # no more than the instances
        (1, 8, 2, 16, 1),  # at least one
    ],
)
def test_the_simulation_takes_the_cores_it_is_given(monkeypatch, cores, numba_threads, processes, envs, threads):
    monkeypatch.setattr("toolimit.learn.training.cores_given", lambda: cores)
    monkeypatch.setattr(numba, "get_num_threads", lambda: numba_threads)
    config = LearningConfig(sim_processes=processes, envs=envs)
    assert config.threads_per_process() == threads
    assert LearningConfig(sim_threads=1, envs=envs).threads_per_process() == 1, "a given count is kept"


def test_only_a_scene_that_takes_threads_gets_them(spade_task):
    config = LearningConfig(sim_threads=1, scene_kwargs={"n_spheres": 20})
    assert config.simulation_kwargs(shipped_task("spade", "3d")) == {"n_spheres": 20, "threads": 1}
    assert LearningConfig(sim_threads=1).simulation_kwargs(spade_task) is None  # planar: none
