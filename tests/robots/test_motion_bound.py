"""The bound on a commanded joint velocity: the Panda's published limits within the margins,
acceleration from rest, braking before a position limit; the model's limits for other robots."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.robots import make_robot
from toolimit.robots.limits import Margins, published_limits
from toolimit.robots.motion_bound import MotionBound

DT = 1.0 / 24.0


def test_the_pandas_bound_is_its_published_limits_within_the_margins():
    panda = make_robot("panda")
    bound, narrowed = MotionBound.of(panda), published_limits("panda").within(Margins())
    np.testing.assert_allclose(bound.velocity, 0.95 * published_limits("panda").velocity)
    np.testing.assert_allclose(bound.acceleration, narrowed.acceleration)
    np.testing.assert_allclose(bound.upper, panda.upper - 0.01)
    authors = MotionBound.of(panda, speed=3.0)  # the authors' span: no acceleration bound
    assert authors.acceleration is None and np.all(authors.velocity == 3.0)


def test_a_robot_without_published_limits_keeps_its_models():
    ur5 = make_robot("ur5")
    bound = MotionBound.of(ur5)
    assert bound.acceleration is None
    np.testing.assert_array_equal(bound.velocity, ur5.velocity_limit)
    np.testing.assert_array_equal(bound.lower, ur5.lower)


def test_full_speed_from_rest_ramps_at_the_acceleration_bound():
    bound = MotionBound(-np.full(2, 10.0), np.full(2, 10.0), np.array([2.0, 2.0]), np.array([6.0, 24.0]))
    q, velocity = np.zeros((1, 2)), np.zeros((1, 2))
    speeds = []
    for _ in range(12):
        q, velocity = bound.step(q, velocity, np.array([[5.0, -5.0]]), DT)
        speeds.append(velocity[0].copy())
    speeds = np.array(speeds)
    np.testing.assert_allclose(speeds[:3, 0], [0.25, 0.5, 0.75])  # 6 rad/s^2 for 1/24 s a step
    np.testing.assert_allclose(speeds[:3, 1], [-1.0, -2.0, -2.0])  # then held at the velocity bound
    assert speeds[-1, 0] == pytest.approx(2.0)


def test_braking_stops_inside_the_range_without_passing_the_acceleration_bound():
    bound = MotionBound(-np.ones(1), np.ones(1), np.array([3.0]), np.array([5.0]))
    q, velocity, path = np.zeros((1, 1)), np.zeros((1, 1)), []
    for _ in range(120):  # full speed towards the upper limit, for longer than it takes to reach it
        q, velocity = bound.step(q, velocity, np.array([[3.0]]), DT)
        path.append(velocity[0, 0])
    changes = np.abs(np.diff(np.r_[0.0, path])) / DT
    assert q[0, 0] <= 1.0 and q[0, 0] > 0.99  # reaches the end, stops there
    assert changes.max() <= 5.0 * (1 + 1e-9), "braking never exceeds the acceleration bound"
    assert path[-1] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("speed", [None, 3.0])
def test_following_a_path_is_stepping_towards_each_next_sample_from_rest(speed: float | None) -> None:
    """``follow`` (stage iii's projection, compiled) gives what stepping one sample at a time
    gives, bit for bit, with and without an acceleration bound; a batch steps each row alone."""
    bound = MotionBound.of(make_robot("panda"), speed=speed)
    rng = np.random.default_rng(4)
    middle = (bound.lower + bound.upper) / 2
    path = middle + np.cumsum(rng.normal(0.0, 0.15, (60, 7)), axis=0)  # runs into the range's ends too
    path[0] = middle
    stepped, velocity = [path[0]], np.zeros((1, 7))
    for sample in path[1:]:
        q, velocity = bound.step(stepped[-1][None], velocity, (sample - stepped[-1])[None] / DT, DT)
        stepped.append(q[0])
    np.testing.assert_array_equal(bound.follow(path, DT), np.array(stepped))
    rows = rng.uniform(bound.lower, bound.upper, (5, 7)), rng.normal(0, 2, (5, 7)), rng.normal(0, 3, (5, 7))
    batch = bound.step(*rows, DT)
    for b in range(5):
        one = bound.step(*(r[b : b + 1] for r in rows), DT)
        np.testing.assert_array_equal(batch[0][b], one[0][0])
        np.testing.assert_array_equal(batch[1][b], one[1][0])
