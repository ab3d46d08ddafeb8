"""Early stopping: checks on their own seeds, a stop on an update boundary, the same updates as a
run without it, and a stopped run that stays stopped."""

from __future__ import annotations

import json
from dataclasses import asdict

import numpy as np
import pytest
import torch

from toolimit.errors import InvalidLearningConfig
from toolimit.learn.early_stop import CHECK_GOAL, CHECK_SEED, CHECK_SUCCESS, CHECK_TRAINING, EarlyStop, StopRule
from toolimit.learn.evaluate import EVALUATION_SEED
from toolimit.learn.kept_policy import SELECTION_SEED
from toolimit.learn.training import CURVE_JSONL, LearningConfig, learn_policy

#: A clone good enough to succeed from the first update on the shipped planar spade.
CLONED = LearningConfig(
    timesteps=0,
    envs=2,
    preset="toolimit",
    clone_rollouts=4,
    clone_noise=0.3,
    clone_steps=500,
    value_steps=20,
    checkpoint_every=1,
    seed=3,  # with the time observed in seconds, the clone of seed 3 passes its first two checks
    stop=StopRule(every=1, episodes=4, training_success=0.0, held=2),
)


def _parameters(model):
    return torch.cat([p.detach().flatten() for p in model.policy.parameters()]).numpy()


def _curve(folder):
    return [json.loads(line) for line in (folder / CURVE_JSONL).read_text().splitlines()]


def _config(**changes):
    return LearningConfig(**{**CLONED.__dict__, **changes})


def test_a_policy_that_has_learnt_stops_on_an_update_boundary(spade_task, tmp_path):
    per_update = spade_task.horizon * 2  # 1 episode per update (toolimit preset) x 2 envs
    stopped = learn_policy(spade_task, tmp_path / "stopped", _config(timesteps=6 * per_update), progress=False)
    record = stopped.record
    assert record["early_stop"]["stopped_at_ppo_env_steps"] == 2 * per_update == record["ppo_env_steps"]
    assert record["early_stop"]["rule"] == {
        "every": 1,
        "episodes": 4,
        "success": 1.0,
        "training_success": 0.0,
        "held": 2,
    }
    curve = _curve(tmp_path / "stopped")
    assert [line["env_steps"] for line in curve] == [per_update, 2 * per_update]
    assert [line[CHECK_SUCCESS] for line in curve] == [1.0, 1.0] and all(line[CHECK_GOAL] > 0 for line in curve)
    assert [line[CHECK_TRAINING] for line in curve] == [line["success_rate"] for line in curve]
    # the same two updates as a run of two updates without early stopping: checks draw nothing
    fixed = learn_policy(
        spade_task, tmp_path / "fixed", _config(timesteps=2 * per_update, early_stop=False), progress=False
    )
    assert "early_stop" not in fixed.record
    np.testing.assert_allclose(_parameters(stopped.model), _parameters(fixed.model), rtol=0, atol=1e-6)
    for with_checks, without in zip(curve, _curve(tmp_path / "fixed"), strict=True):
        assert {k: v for k, v in with_checks.items() if not k.startswith("check_")} == pytest.approx(without)
    # run again, it stays stopped: no step more, no line more
    again = learn_policy(spade_task, tmp_path / "stopped", _config(timesteps=6 * per_update), progress=False)
    assert again.record["resumed"] and again.record["ppo_env_steps"] == 2 * per_update
    assert _curve(tmp_path / "stopped") == curve


def test_a_check_passes_only_with_the_training_episodes_succeeding_too(spade_task):
    """Checks read back from a curve: a mean that succeeds while the training episodes fail is no pass."""
    rule = StopRule(every=1, episodes=2, training_success=0.8, held=2)

    def line(steps, check, training):
        return {"env_steps": steps, "success_rate": training, CHECK_SUCCESS: check, CHECK_TRAINING: training}

    def stop(curve):
        return EarlyStop(spade_task, rule, curve)

    assert stop([line(10, 1.0, 0.5), line(20, 1.0, 0.9)]).stopped_at is None  # one pass in a row
    assert stop([line(10, 1.0, 0.9), line(20, 1.0, 0.9)]).stopped_at == 20
    assert stop([line(10, 1.0, 0.9), line(20, 0.95, 1.0)]).stopped_at is None
    assert stop([line(10, 1.0, 0.9), line(20, 0.95, 1.0), line(30, 1.0, 0.8), line(40, 1.0, 0.85)]).stopped_at == 40


def test_a_rule_never_met_spends_the_whole_budget(spade_task, tmp_path):
    per_update = spade_task.horizon * 2
    config = _config(timesteps=3 * per_update, clone_steps=20, stop=StopRule(every=2, episodes=2, held=1))
    outcome = learn_policy(spade_task, tmp_path, config, progress=False)
    assert outcome.record["early_stop"]["stopped_at_ppo_env_steps"] is None
    assert outcome.record["ppo_env_steps"] == 3 * per_update
    checked = [line["env_steps"] for line in _curve(tmp_path) if CHECK_SUCCESS in line]
    assert checked == [2 * per_update]  # every second update


@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"every": 0}, "stop_every"),
        ({"episodes": 0}, "stop_episodes"),
        ({"held": 1.5}, "stop_held"),
        ({"success": 0.0}, "stop_success"),
        ({"success": 1.2}, "stop_success"),
    ],
)
def test_a_rule_no_run_can_use_is_refused(changes, field):
    with pytest.raises(InvalidLearningConfig) as error:
        StopRule(**changes)
    assert error.value.field == field


def test_a_config_rebuilt_from_its_record_has_its_rule():
    config = LearningConfig(stop=StopRule(every=3))
    assert LearningConfig(**asdict(config)) == config  # as notebooks and learning.json hand it back
    with pytest.raises(InvalidLearningConfig):
        LearningConfig(stop=3)


class _ScriptedChecks:
    """Stands in for the checks' rollout: the given success rates, one per check, in order."""

    def __init__(self, rates):
        self.rates = list(rates)

    def __call__(self, model, env, deterministic=True):
        rate = self.rates.pop(0)

        class Outcome:
            def record(self):
                return {"success_rate": rate, "goal_reward_mean": 10.0 * rate}

        return Outcome()


class _ScriptedSelection:
    """Stands in for the final choice's rollouts: (best check's, last update's) success rates, one
    pair per run end, in order."""

    def __init__(self, pairs):
        self.rates = [rate for pair in pairs for rate in pair]

    def __call__(self, model, task, episodes, scene_kwargs):
        rate = self.rates.pop(0)
        return {"success_rate": rate, "goal_reward_mean": 10.0 * rate}


def test_the_run_keeps_its_best_checked_policy_and_continues_from_its_last(spade_task, tmp_path, monkeypatch):
    """Checks of 0.5, 1.0, 0.25, 1.0, 0.0: the policy of the 4th (the best, latest among equals) is
    the run's when it does better than the last update's on the selection episodes; the last
    update's stays the checkpoint a larger budget continues from."""
    per_update = spade_task.horizon * 2
    never = StopRule(every=1, episodes=2, training_success=0.0, held=9)
    monkeypatch.setattr("toolimit.learn.early_stop.rollout", _ScriptedChecks([0.5, 1.0, 0.25, 1.0, 0.0]))
    monkeypatch.setattr("toolimit.learn.kept_policy.selection_outcome", _ScriptedSelection([(0.9, 0.6)]))
    config = _config(timesteps=6 * per_update, clone_steps=20, stop=never)
    outcome = learn_policy(spade_task, tmp_path / "run", config, progress=False)
    kept = outcome.record["kept_policy"]
    assert kept["policy"] == "best_check" and kept["env_steps"] == 4 * per_update
    assert kept["best_check"]["success_rate"] == 1.0
    assert kept["selection"]["best_check"]["success_rate"] == 0.9
    assert kept["selection"]["last_update"]["success_rate"] == 0.6
    assert {p.name for p in (tmp_path / "run").glob("best*")} == {"best.json", f"best-{4 * per_update}.safetensors"}
    # the kept policy is the 4th update's, as a run of four updates without checks has it
    four = learn_policy(spade_task, tmp_path / "four", _config(**{**config.__dict__, "timesteps": 4 * per_update,
                                                                   "early_stop": False}), progress=False)
    np.testing.assert_allclose(_parameters(outcome.model), _parameters(four.model), rtol=0, atol=1e-6)
    six = learn_policy(spade_task, tmp_path / "six", _config(**{**config.__dict__, "early_stop": False}), progress=False)
    assert not np.allclose(_parameters(outcome.model), _parameters(six.model))
    assert json.loads((tmp_path / "run" / "checkpoint.json").read_text())["model"] == "checkpoint.safetensors"
    # a larger budget continues from the last update, not from the kept policy; a later check at
    # the kept one's success (checks after updates 6 and 7: 0.0, 1.0) takes its place
    monkeypatch.setattr("toolimit.learn.early_stop.rollout", _ScriptedChecks([0.0, 1.0]))
    monkeypatch.setattr("toolimit.learn.kept_policy.selection_outcome", _ScriptedSelection([(0.9, 0.6)]))
    longer = learn_policy(spade_task, tmp_path / "run", _config(**{**config.__dict__, "timesteps": 8 * per_update}),
                          progress=False)
    assert longer.record["resumed"] and longer.record["ppo_env_steps"] == 8 * per_update
    assert longer.record["kept_policy"]["env_steps"] == 7 * per_update
    seven = learn_policy(spade_task, tmp_path / "seven", _config(**{**config.__dict__, "timesteps": 7 * per_update,
                                                                     "early_stop": False}), progress=False)
    np.testing.assert_allclose(_parameters(longer.model), _parameters(seven.model), rtol=0, atol=1e-6)
    assert {p.name for p in (tmp_path / "run").glob("best*")} == {"best.json", f"best-{7 * per_update}.safetensors"}


@pytest.mark.parametrize("selection", [(0.6, 0.9), (0.75, 0.75)], ids=["last-does-better", "equal"])
def test_a_best_check_that_does_no_better_on_the_selection_episodes_gives_way_to_the_last_update(
    spade_task, tmp_path, monkeypatch, selection
):
    per_update = spade_task.horizon * 2
    monkeypatch.setattr("toolimit.learn.early_stop.rollout", _ScriptedChecks([1.0, 0.5, 0.5]))
    monkeypatch.setattr("toolimit.learn.kept_policy.selection_outcome", _ScriptedSelection([selection]))
    config = _config(timesteps=3 * per_update, clone_steps=20, stop=StopRule(every=1, episodes=2, held=9))
    outcome = learn_policy(spade_task, tmp_path / "run", config, progress=False)
    kept = outcome.record["kept_policy"]
    assert kept["policy"] == "last_update" and kept["env_steps"] == 3 * per_update
    assert kept["best_check"]["env_steps"] == per_update, "the best check stays on record"
    last = learn_policy(spade_task, tmp_path / "last", _config(**{**config.__dict__, "early_stop": False}),
                        progress=False)
    np.testing.assert_allclose(_parameters(outcome.model), _parameters(last.model), rtol=0, atol=1e-6)


def test_the_selection_rolls_both_candidates_out_and_keeps_the_better(spade_task, tmp_path, monkeypatch):
    """The real selection (checks scripted so that the best is the first update's): each candidate
    rolled out on the selection episodes, the record's choice the one that did better."""
    per_update = spade_task.horizon * 2
    monkeypatch.setattr("toolimit.learn.early_stop.rollout", _ScriptedChecks([1.0, 0.0, 0.0]))
    config = _config(timesteps=3 * per_update, clone_steps=20, selection_episodes=3,
                     stop=StopRule(every=1, episodes=2, held=9))
    kept = learn_policy(spade_task, tmp_path, config, progress=False).record["kept_policy"]
    selection = kept["selection"]
    assert selection["episodes"] == 3 and selection["seed"] == SELECTION_SEED
    ranked = {name: (selection[name]["success_rate"], selection[name]["goal_reward_mean"])
              for name in ("best_check", "last_update")}
    assert kept["policy"] == ("best_check" if ranked["best_check"] > ranked["last_update"] else "last_update")
    assert SELECTION_SEED not in {EVALUATION_SEED} | {CHECK_SEED + update for update in range(10**5)}


def test_without_keep_best_the_run_is_its_last_update(spade_task, tmp_path, monkeypatch):
    per_update = spade_task.horizon * 2
    monkeypatch.setattr("toolimit.learn.early_stop.rollout", _ScriptedChecks([1.0, 0.0]))
    config = _config(timesteps=2 * per_update, clone_steps=20, keep_best=False, stop=StopRule(every=1, episodes=2, held=9))
    outcome = learn_policy(spade_task, tmp_path, config, progress=False)
    assert "kept_policy" not in outcome.record and not list(tmp_path.glob("best*"))
    assert json.loads((tmp_path / "checkpoint.json").read_text())["model"] == "policy.safetensors"
