"""Policies without pickle: the safetensors model file, a stable-baselines3 zip only on request,
and names planted in an output folder's records refused."""

from __future__ import annotations

import base64
import json
import pickle
import shutil
import zipfile

import numpy as np
import pytest
import torch

from toolimit.cli import main
from toolimit.errors import InputError
from toolimit.learn.kept_policy import BEST_JSON, KeptPolicy
from toolimit.learn.policy_file import load_model, save_model
from toolimit.learn.training import LearningConfig, learn_policy, load_policy

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


@pytest.fixture(scope="module")
def learned(tmp_path_factory, spade_task_module):
    """A finished tiny run (two updates): its folder and outcome."""
    folder = tmp_path_factory.mktemp("learned")
    config = LearningConfig(**{**TINY.__dict__, "timesteps": 2 * spade_task_module.horizon * 2})
    return folder, learn_policy(spade_task_module, folder, config, progress=False)


@pytest.fixture(scope="module")
def spade_task_module():
    from toolimit.learn import shipped_task

    return shipped_task("spade", "planar")


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_a_model_file_round_trips_policy_optimiser_and_settings(learned, tmp_path):
    folder, outcome = learned
    model = outcome.model
    save_model(model, tmp_path / "m.safetensors")
    loaded = load_model(tmp_path / "m.safetensors")
    for name, tensor in model.policy.state_dict().items():
        torch.testing.assert_close(loaded.policy.state_dict()[name], tensor, rtol=0, atol=0)
    ours, theirs = model.policy.optimizer.state_dict(), loaded.policy.optimizer.state_dict()
    assert ours["state"].keys() == theirs["state"].keys() and ours["state"], "Adam's moments are kept"
    for index, state in ours["state"].items():
        for key, value in state.items():
            torch.testing.assert_close(theirs["state"][index][key], value, rtol=0, atol=0)
    assert [g["lr"] for g in theirs["param_groups"]] == [g["lr"] for g in ours["param_groups"]]
    assert type(loaded.policy.optimizer) is type(model.policy.optimizer)
    assert loaded.n_steps == model.n_steps and loaded.batch_size == model.batch_size
    assert loaded.num_timesteps == model.num_timesteps
    observation = np.zeros(model.observation_space.shape, dtype=np.float32)
    np.testing.assert_array_equal(loaded.predict(observation, deterministic=True)[0],
                                  model.predict(observation, deterministic=True)[0])
    assert not zipfile.is_zipfile(folder / "policy.safetensors")


def _sb3_zip_with_payload(model, path, marker):
    """A stable-baselines3 zip of ``model`` whose ``data`` carries a pickled call creating ``marker``."""
    model.save(path)
    with zipfile.ZipFile(path) as archive:
        entries = {name: archive.read(name) for name in archive.namelist()}
    data = json.loads(entries["data"])
    payload = pickle.dumps(_Payload(str(marker)))
    data["policy_class"] = {":type:": "<class 'type'>", ":serialized:": base64.b64encode(payload).decode()}
    entries["data"] = json.dumps(data).encode()
    with zipfile.ZipFile(path, "w") as archive:
        for name, content in entries.items():
            archive.writestr(name, content)


class _Payload:
    """Unpickled, it creates the file ``marker`` (what an attacker's code could do instead)."""

    def __init__(self, marker: str):
        self.marker = marker

    def __reduce__(self):
        return exec, (f"open({self.marker!r}, 'w').close()",)


def test_a_zip_carrying_a_payload_is_refused_in_one_line_and_never_runs(learned, tmp_path, capsys):
    folder, outcome = learned
    shared = tmp_path / "shared"
    shared.mkdir()
    shutil.copyfile(folder / "task.npz", shared / "task.npz")
    marker = tmp_path / "payload-ran"
    _sb3_zip_with_payload(outcome.model, shared / "policy.zip", marker)
    assert main(["evaluate", "--policy", str(shared), "--episodes", "1"]) == 2
    line = _one_line(capsys)
    assert "policy.zip" in line and "can run code" in line and "--trust-sb3-zip" in line
    assert not marker.exists()
    # the payload is real: asked for explicitly, SB3's loading runs it (after a warning)
    code = main(["evaluate", "--policy", str(shared), "--episodes", "1", "--trust-sb3-zip"])
    assert marker.exists()
    err = capsys.readouterr().err
    assert "warning" in err and "can run code" in err
    assert code in (0, 2)


def test_an_earlier_toolimit_zip_loads_only_when_trusted(learned, tmp_path, capsys):
    folder, outcome = learned
    old = tmp_path / "old"
    old.mkdir()
    shutil.copyfile(folder / "task.npz", old / "task.npz")
    outcome.model.save(old / "policy.zip")
    with pytest.raises(InputError, match="can run code"):
        load_policy(old)
    model, _ = load_policy(old, trust_sb3_zip=True)
    np.testing.assert_array_equal(model.policy.state_dict()["log_std"].numpy(),
                                  outcome.model.policy.state_dict()["log_std"].numpy())


@pytest.mark.parametrize("content", [b"", b"garbage" * 10, b"PK\x03\x04 not a zip", json.dumps({"a": 1}).encode()])
def test_a_garbage_policy_file_is_one_line(learned, tmp_path, capsys, content):
    folder, _ = learned
    bad = tmp_path / "bad"
    bad.mkdir()
    shutil.copyfile(folder / "task.npz", bad / "task.npz")
    (bad / "policy.safetensors").write_bytes(content)
    assert main(["evaluate", "--policy", str(bad), "--episodes", "1"]) == 2
    assert "policy.safetensors" in _one_line(capsys)
    (bad / "policy.safetensors").unlink()
    (bad / "policy.zip").write_bytes(content)
    assert main(["evaluate", "--policy", str(bad), "--episodes", "1", "--trust-sb3-zip"]) == 2
    assert "policy.zip" in capsys.readouterr().err.strip().splitlines()[-1]


def test_a_model_of_another_task_is_refused(learned, tmp_path, capsys):
    folder, _ = learned
    other = tmp_path / "other"
    shutil.copytree(folder, other)
    from toolimit.learn import shipped_task

    shipped_task("scythe", "planar").save(other / "task.npz")
    assert main(["evaluate", "--policy", str(other), "--episodes", "1"]) == 2
    assert "learnt on spade/planar" in _one_line(capsys)


@pytest.mark.parametrize("planted", ["outside", "absolute", "symlink", "old-zip"])
def test_a_checkpoint_naming_a_model_outside_its_folder_is_refused(learned, tmp_path, spade_task_module, planted):
    folder, _ = learned
    run = tmp_path / "run"
    shutil.copytree(folder, run)
    outside = tmp_path / "elsewhere.safetensors"
    shutil.copyfile(folder / "policy.safetensors", outside)
    names = {"outside": "../elsewhere.safetensors", "absolute": str(outside), "symlink": "link.safetensors",
             "old-zip": "checkpoint.zip"}
    if planted == "symlink":
        (run / "link.safetensors").symlink_to(outside)
    state = json.loads((run / "checkpoint.json").read_text())
    state["model"] = names[planted]
    (run / "checkpoint.json").write_text(json.dumps(state))
    longer = LearningConfig(**{**TINY.__dict__, "timesteps": 3 * spade_task_module.horizon * 2})
    with pytest.raises(InputError) as error:
        learn_policy(spade_task_module, run, longer, progress=False)
    assert "checkpoint.json" in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize("planted", ["../victim.txt", "/tmp/toolimit-victim-never.txt"])
def test_a_planted_best_record_deletes_and_reads_nothing_outside(learned, tmp_path, spade_task_module, planted):
    folder, outcome = learned
    run = tmp_path / "run"
    run.mkdir()
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    (run / BEST_JSON).write_text(json.dumps({"env_steps": 1, "success_rate": 0.0, "goal_reward_mean": 0.0,
                                             "model": planted}))
    with pytest.raises(InputError, match="best.json"):
        KeptPolicy(run, spade_task_module, episodes=1)
    assert victim.read_text() == "keep me"
