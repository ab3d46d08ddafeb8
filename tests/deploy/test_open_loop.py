"""Open-loop replay of joint commands in a learning task's scene: the reference motion delivers, an
arm that stays at rest does not, the commands are interpolated and held, bad commands are refused."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.deploy.open_loop import commands_at, replay_open_loop
from toolimit.learn import shipped_task


@pytest.fixture(scope="module")
def panda_spade():
    return shipped_task("spade", "3d")


def test_the_reference_motion_delivers_and_an_arm_at_rest_does_not(panda_spade):
    task = panda_spade
    times = np.arange(len(task.reference_q)) * task.control_dt
    moved = replay_open_loop(times, task.reference_q, task, episodes=3)
    assert moved.successes.mean() >= 2 / 3 and moved.goal_rewards.mean() >= 10.0
    still = np.tile(task.reference_q[0], (2, 1))
    rest = replay_open_loop(times[[0, -1]], still, task, episodes=3)
    assert not rest.successes.any() and rest.goal_rewards.max() < 1.0
    assert moved.record()["episode_duration_s"] == pytest.approx(task.horizon * task.control_dt)


def test_commands_are_interpolated_and_held():
    times = np.array([0.0, 1.0, 2.0])
    positions = np.array([[0.0, 1.0], [1.0, 1.0], [1.0, 3.0]])
    at = commands_at(times, positions, np.array([-1.0, 0.5, 1.5, 5.0]))
    np.testing.assert_allclose(at, [[0.0, 1.0], [0.5, 1.0], [1.0, 2.0], [1.0, 3.0]])


def test_bad_commands_are_refused(panda_spade):
    with pytest.raises(ValueError, match=r"commands must be \(K, 7\) positions"):
        replay_open_loop(np.arange(3.0), np.zeros((3, 6)), panda_spade)
    with pytest.raises(ValueError, match="increasing times"):
        replay_open_loop(np.zeros(3), np.zeros((3, 7)), panda_spade)
