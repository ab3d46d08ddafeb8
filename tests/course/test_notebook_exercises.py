"""The notebooks' exercise checks (course/notebook_checks.py): a right answer passes, a wrong one
gets a message and fails, an unwritten one says so; none raises, so a student's notebook runs."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

COURSE = Path(__file__).resolve().parents[2] / "course"
sys.path.insert(0, str(COURSE))
import grade  # noqa: E402
import notebook_checks  # noqa: E402

sys.path.remove(str(COURSE))


def unwritten(*args, **kwargs):
    raise NotImplementedError("exercise: write this part")


def keypoints(demo, fraction=0.05):
    speed = demo.speed()
    before, here, after = speed[:-2], speed[1:-1], speed[2:]
    is_max = (here > before) & (here > after) & (here >= np.quantile(speed, 1.0 - fraction))
    is_min = (here < before) & (here < after) & (here <= np.quantile(speed, fraction))
    return np.unique(np.concatenate([[0, demo.n_frames - 1], 1 + np.flatnonzero(is_max | is_min)])).astype(int)


def gae(rewards, values, episode_starts, last_values, dones, gamma, gae_lambda, boundaries=True):
    advantages, running = np.zeros_like(rewards, dtype=float), np.zeros(rewards.shape[1])
    for t in reversed(range(len(rewards))):
        last = t == len(rewards) - 1
        not_done = 1.0 - (dones if last else episode_starts[t + 1]) if boundaries else 1.0
        next_values = last_values if last else values[t + 1]
        running = rewards[t] + gamma * next_values * not_done - values[t] + gamma * gae_lambda * not_done * running
        advantages[t] = running
    return advantages, advantages + values


@pytest.fixture(scope="module")
def demo():
    from toolimit.demos import synthesize_demo

    return synthesize_demo("spade", seed=0)


def test_keypoints_check(demo, capsys):
    assert notebook_checks.check_velocity_keypoints(keypoints, demo)
    assert "velocity keypoints: exercise passed" in capsys.readouterr().out
    assert not notebook_checks.check_velocity_keypoints(unwritten, demo)
    assert "not written yet" in capsys.readouterr().out
    assert not notebook_checks.check_velocity_keypoints(lambda d, f=0.05: keypoints(d, f)[1:-1], demo)
    assert "missing [0," in capsys.readouterr().out
    assert not notebook_checks.check_velocity_keypoints(lambda d, f=0.05: np.array([d.n_frames]), demo)
    assert f"frames must lie in 0..{demo.n_frames - 1}" in capsys.readouterr().out


def test_gae_check(capsys):
    assert notebook_checks.check_gae(gae)
    assert not notebook_checks.check_gae(lambda *args: gae(*args, boundaries=False))
    assert "first wrong step going backwards" in capsys.readouterr().out
    assert not notebook_checks.check_gae(lambda *args: 0.0)
    assert "expected a tuple (advantages, returns)" in capsys.readouterr().out


def test_success_rule_check(capsys):
    def rule(in_box, count):
        met = np.asarray(in_box) >= count
        return met.sum(axis=1) >= 0.5 * met.shape[1]

    assert notebook_checks.check_spade_success(rule)
    assert not notebook_checks.check_spade_success(lambda in_box, count: np.asarray(in_box).max(axis=1) >= count)
    assert "expected False, got True" in capsys.readouterr().out
    assert not notebook_checks.check_spade_success(unwritten)


def test_solution_markers_are_stripped_and_checked():
    source = "def f(x):\n    ### BEGIN SOLUTION\n    return 2 * x\n    ### END SOLUTION\n\nprint(f)\n"
    stripped = grade.strip_solutions(source)
    assert stripped == 'def f(x):\n    raise NotImplementedError("exercise: write this part")\n\nprint(f)\n'
    with pytest.raises(ValueError, match="without its"):
        grade.strip_solutions("    ### BEGIN SOLUTION\n    return 1\n")


def test_every_exercise_notebook_holds_one_solution_per_check():
    notebooks = grade.exercise_notebooks()
    assert [path.name[:2] for path in notebooks] == ["01", "02", "03", "04", "05", "06"]
    for path in notebooks:
        text = path.read_text()
        assert text.count("### BEGIN SOLUTION") == text.count("### END SOLUTION") >= 1, path.name
        assert text.count("check_") >= 2 * text.count("### BEGIN SOLUTION"), path.name
