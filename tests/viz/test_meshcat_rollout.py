"""meshcat view of a policy's episode: the recorded rollout and its self-contained HTML page."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from test_meshcat_robot import clips_of, transforms_of  # this folder's (pytest puts it on sys.path)

from toolimit.learn import shipped_task
from toolimit.robots import make_robot
from toolimit.viz.meshcat_rollout import record_rollout, rollout_html

STEPS = 12


@pytest.fixture(scope="module")
def hammer_task():
    """The shipped Panda hammer task cut to its first STEPS control steps (a short episode)."""
    task = shipped_task("hammer", "3d")
    return dataclasses.replace(task, reference_q=task.reference_q[:STEPS + 1], horizon=STEPS)


class ZeroPolicy:
    """Stands still; records the ``deterministic`` flag it was asked for."""

    def __init__(self, n_joints: int):
        self.n_joints, self.modes = n_joints, set()

    def predict(self, observation, deterministic=False):
        self.modes.add(deterministic)
        return np.zeros((len(observation), self.n_joints), dtype=np.float32), None


def test_tracking_rollout_records_joints_and_snapshots_repeatably(hammer_task):
    rollout = record_rollout(hammer_task, seed=3)
    assert rollout.q.shape == (STEPS + 1, 7) and len(rollout.snapshots) == STEPS + 1
    assert rollout.goal_rewards.shape == (STEPS,) and isinstance(rollout.success, bool)
    # the controller tracks: the swing moves a joint by 1.1 rad in these steps; the reference uses the
    # whole acceleration budget, so the start's noise is taken out only as the swing slows
    travel = np.abs(hammer_task.reference_q[-1] - hammer_task.reference_q[0]).max()
    assert np.abs(rollout.q[-1] - hammer_task.reference_q[-1]).max() < 0.15 * travel
    assert "plate_center" in rollout.snapshots[-1]
    again = record_rollout(hammer_task, seed=3)
    np.testing.assert_array_equal(again.q, rollout.q)
    assert not np.array_equal(record_rollout(hammer_task, seed=4).q[0], rollout.q[0])  # reset noise


def test_a_policy_acts_in_the_asked_mode(hammer_task):
    policy = ZeroPolicy(7)
    rollout = record_rollout(hammer_task, policy, deterministic=False, seed=0)
    assert policy.modes == {False}
    np.testing.assert_array_equal(rollout.q, np.repeat(rollout.q[:1], STEPS + 1, axis=0))  # zero velocity


def test_html_animates_robot_tool_and_world(hammer_task, tmp_path, html_commands):
    rollout = record_rollout(hammer_task, seed=0)
    path = rollout_html(tmp_path / "rollout.html", hammer_task, rollout, stride=4)
    commands = html_commands(path)
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    assert any(p.startswith("/meshcat/robot/visuals/panda_link") for p in objects)
    assert {"/meshcat/world/board", "/meshcat/world/nail/plate"} <= objects
    clips = clips_of(commands)
    tool = transforms_of(clips["/meshcat/tool"])
    assert len(tool) == len(range(0, STEPS + 1, 4))  # steps 0, 4, 8, 12 (the last one is kept)
    assert clips["/meshcat/tool"]["fps"] == pytest.approx(24.0 / 4)
    robot = make_robot("panda", tool="hammer")
    for frame, step in zip(tool, (0, 4, 8, 12)):
        np.testing.assert_allclose(frame[:3, 3], robot.tool_pose(rollout.q[step], hammer_task.base)[0], atol=1e-5)
    assert "/meshcat/world/nail/plate" in clips  # the world moves with the episode


def test_bad_inputs_write_nothing(hammer_task, tmp_path):
    rollout = record_rollout(hammer_task, seed=0)
    target = tmp_path / "bad.html"
    with pytest.raises(ValueError, match="stride must be an integer >= 1"):
        rollout_html(target, hammer_task, rollout, stride=0)
    short = dataclasses.replace(rollout, q=rollout.q[:, :3])
    with pytest.raises(ValueError, match=r"rollout q must be \(H\+1, 7\)"):
        rollout_html(target, hammer_task, short)
    assert not target.exists()
