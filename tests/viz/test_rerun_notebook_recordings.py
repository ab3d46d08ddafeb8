"""The recordings notebooks 02 and 04 write: sampling, one sample's replay, a tracking rollout, goal rewards."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from toolimit.demos import synthesize_demo
from toolimit.viz.rerun_alignment import save_sample_replay_recording, save_sampling_recording
from toolimit.viz.rerun_learning import save_goal_rewards_recording, save_tracking_recording

RERUN_CLI = Path(sys.executable).parent / "rerun"


def printed_entities(path: Path) -> str:
    """``rerun rrd print`` of a recording (entity paths and components)."""
    printed = subprocess.run([RERUN_CLI, "rrd", "print", path], capture_output=True, text=True, timeout=60)
    assert printed.returncode == 0, printed.stderr
    return printed.stdout


@pytest.fixture(autouse=True)
def rerun_on(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("RERUN", raising=False)


def test_sampling_and_one_sample_replay(tmp_path: Path) -> None:
    demo = synthesize_demo("spade", seed=0)
    samples = {"sand": np.zeros((5, 3)), "box": np.ones((5, 3))}
    path = save_sampling_recording(tmp_path / "sampling.rrd", demo, np.array([0, 10, 20]), samples)
    assert path == tmp_path / "sampling.rrd"
    text = printed_entities(path)
    for entity in ("demo/head", "demo/keypoints", "samples/sand", "samples/box"):
        assert entity in text
    snapshots = [{"grains": np.zeros((4, 3)), "count": np.array(2.0)} for _ in range(3)]
    replayed = save_sample_replay_recording(tmp_path / "one.rrd", demo, {"box": np.ones(3), "yaw": 0.3}, snapshots, 1 / 24)
    text = printed_entities(replayed)
    assert "scene/params/box" in text and "replay/tool" in text and "replay/state/grains" in text
    assert "scene/params/yaw" not in text  # a uniform parameter is not a point
    with pytest.raises(ValueError, match="snapshots for a motion of"):
        save_sample_replay_recording(tmp_path / "bad.rrd", demo, {}, snapshots * 100, 1 / 24)


def test_tracking_rollout_and_goal_rewards(tmp_path: Path) -> None:
    executed, reference = np.zeros((6, 2)), np.ones((4, 2))
    path = save_tracking_recording(tmp_path / "tracking.rrd", ("a", "b"), executed, reference, np.arange(5.0))
    text = printed_entities(path)
    for entity in ("joints/a/executed", "joints/b/reference", "goal_reward"):
        assert entity in text
    with pytest.raises(ValueError, match="goal rewards for 5 steps"):
        save_tracking_recording(tmp_path / "bad.rrd", ("a", "b"), executed, reference, np.arange(4.0))
    rewards = save_goal_rewards_recording(tmp_path / "rewards.rrd", {"one/deterministic": np.array([1.0, 2.0])})
    assert "goal_reward_per_episode/one/deterministic" in printed_entities(rewards)


def test_nothing_is_written_when_rerun_is_off(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RERUN", "off")
    assert save_goal_rewards_recording(tmp_path / "off.rrd", {"x": np.ones(2)}) is None
    assert not (tmp_path / "off.rrd").exists()
