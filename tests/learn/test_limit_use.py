"""Limit accounting of rollouts: share of steps past the robot's limits and the largest ratios."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.learn.limit_use import limit_use
from toolimit.robots import make_robot
from toolimit.robots.limits import published_limits

DT = 1.0 / 24.0


def test_a_jump_to_full_speed_is_past_the_pandas_acceleration_limit():
    panda = make_robot("panda")
    joints = np.tile(panda.q_neutral, (2, 11, 1))
    # episode 0: joint 2 at its velocity limit from the first step (from rest); episode 1 at rest
    joints[0, :, 1] += np.arange(11) * panda.velocity_limit[1] * DT
    use = limit_use(joints, DT, panda)
    acceleration = panda.velocity_limit[1] / DT / published_limits("panda").acceleration[1]
    assert use.acceleration_ratio[0] == pytest.approx(acceleration)  # 6.96: 2.175 rad/s in 1/24 s
    assert use.velocity_ratio[0] == pytest.approx(1.0)
    assert use.share_past.tolist() == [0.1, 0.0]  # only the first step: the velocity is at, not past, its limit
    record = use.record()
    assert record["share_of_steps_past_limits"] == pytest.approx(0.05)
    assert record["max_acceleration_ratio"] == pytest.approx(acceleration)


def test_a_robot_without_published_acceleration_limits_counts_velocity_alone():
    ur5 = make_robot("ur5")
    joints = np.tile(ur5.q_neutral, (1, 5, 1))
    joints[0, :, 0] += np.arange(5) * 1.5 * ur5.velocity_limit[0] * DT
    use = limit_use(joints, DT, ur5)
    assert use.acceleration_ratio is None and use.record()["max_acceleration_ratio"] is None
    assert use.share_past.tolist() == [1.0] and use.velocity_ratio[0] == pytest.approx(1.5)
