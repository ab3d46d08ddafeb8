"""Multi-start tracking: base guesses, best start kept, footprints, roll-symmetric tools, results."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from toolimit.robots import make_robot
from toolimit.trajopt import PoseTargets, SqpOptions, TrackOptions, TrajectoryResult, base_guesses, track
from toolimit.trajopt.track import base_in_footprints

from trajopt_helpers import FPS, reachable_path, targets_of

QUICK = SqpOptions(max_iterations=15)


#: One joint initialisation per base start: these tests count and compare the starts themselves.
HOLD = ("hold",)

def test_base_guesses_follow_the_benchmark_scheme():
    """PROBLEM.md: ring of 8 at 0.6 m around the targets' centre, guess 0 towards the origin, and
    the tip of the start pose on the ray from the base to the centre."""
    link8 = pin.SE3(np.eye(3), np.array([0, 0, 0.107]))
    mount = pin.SE3(pin.rpy.rpyToMatrix(-np.pi / 2, 0, -np.pi / 4), np.zeros(3))
    tip = pin.SE3(pin.rpy.rpyToMatrix(-np.pi / 6, 0, 0), np.array([0, 0.045, 0.40]))
    placement = link8 * mount * tip
    panda = make_robot("panda", tool_placement=placement, base_height=0.0)  # PROBLEM.md: on the floor
    np.testing.assert_allclose(panda.tool_pose(panda.q_neutral, np.zeros(3))[0], [0.306885, -0.4, 0.635276], atol=1e-5)
    positions = np.array([[1.0, 1.0, 0.3], [1.4, 0.6, 0.5]])
    targets = PoseTargets(positions, np.tile(np.eye(3), (2, 1, 1)), FPS)
    guesses = base_guesses(panda, targets)
    centre = np.array([1.2, 0.8])
    assert guesses.shape == (8, 3)
    np.testing.assert_allclose(np.linalg.norm(guesses[:, :2] - centre, axis=1), 0.6)
    assert np.linalg.norm(guesses[0, :2]) < np.linalg.norm(centre)  # towards the origin
    for guess in guesses:
        tip = panda.tool_pose(panda.q_neutral, guess)[0]
        ray = centre - guess[:2]
        arm = tip[:2] - guess[:2]
        assert ray[0] * arm[1] - ray[1] * arm[0] == pytest.approx(0.0, abs=1e-9)
        assert np.dot(ray, tip[:2] - guess[:2]) > 0


def test_random_starts_are_seeded_and_planar_guesses_stay_in_plane(planar3, panda):
    targets = PoseTargets(np.array([[0.5, 0.3, 0.4]]), np.eye(3)[None], FPS)
    first = base_guesses(panda, targets, count=12, rng=np.random.default_rng(5))
    again = base_guesses(panda, targets, count=12, rng=np.random.default_rng(5))
    np.testing.assert_array_equal(first, again)
    np.testing.assert_array_equal(first[:8], base_guesses(panda, targets))
    with pytest.raises(ValueError, match="rng"):
        base_guesses(panda, targets, count=12)
    planar = base_guesses(planar3, targets, count=5)
    assert np.all(planar[:, 1:] == 0.0)
    np.testing.assert_allclose(planar[:, 0], 0.5 + np.linspace(-0.6, 0.6, 5))


def _reachable_targets(robot, base):
    path = reachable_path(robot, 20)
    return path, targets_of(robot, path, base)


def test_multistart_keeps_the_best_start(planar3):
    path, targets = _reachable_targets(planar3, np.array([0.3, 0.0, 0.0]))
    guesses = np.array([[-2.0, 0, 0], [0.32, 0, 0], [2.5, 0, 0]])
    one_step = SqpOptions(max_iterations=1)  # each start stays in its own neighbourhood
    options = TrackOptions(sqp=one_step, q_start=path[0], merge_distance=0.0, initialisations=HOLD)
    result = track(planar3, targets, options, guesses=guesses)
    costs = result.statistics.start_costs
    assert len(costs) == 3
    assert result.statistics.cost == min(costs)
    assert result.statistics.start_index == 1 == int(np.argmin(costs))
    assert max(costs) > 1.5 * min(costs), "the far starts should end worse"
    assert result.statistics.cost_terms["total"] == pytest.approx(result.statistics.cost)
    assert isinstance(result, TrajectoryResult) and result.q.shape == (21, 3) and result.v.shape == (20, 3)


def test_runs_joining_a_converged_basin_stop_early(planar3):
    path, targets = _reachable_targets(planar3, np.array([0.3, 0.0, 0.0]))
    guesses = np.array([[0.31, 0, 0], [0.29, 0, 0]])
    options = TrackOptions(sqp=SqpOptions(), q_start=path[0], merge_distance=0.05, initialisations=HOLD)
    result = track(planar3, targets, options, guesses=guesses)
    assert result.statistics.starts_merged == 1


def test_bases_inside_scene_footprints_are_rejected(planar3):
    footprints = np.array([[0.3, 0.0, 0.2, 5.0, 0.0]])  # a wide element around x = 0.3
    assert base_in_footprints(np.array([0.35, 0.0, 0.0]), footprints) == 0
    assert base_in_footprints(np.array([0.6, 0.0, 0.0]), footprints) is None
    turned = np.array([[0.0, 0.0, 1.0, 0.1, np.pi / 2]])  # long along world y after the yaw
    assert base_in_footprints(np.array([0.0, 0.8, 0.0]), turned) == 0
    assert base_in_footprints(np.array([0.8, 0.0, 0.0]), turned) is None
    path, targets = _reachable_targets(planar3, np.array([0.3, 0.0, 0.0]))
    guesses = np.array([[0.3, 0, 0], [1.2, 0, 0]])
    options = TrackOptions(sqp=QUICK, q_start=path[0], merge_distance=0.0, initialisations=HOLD)
    free = track(planar3, targets, options, guesses=guesses)
    around_best = np.array([[free.base[0], 0.0, 0.01, 5.0, 0.0]])
    options = TrackOptions(sqp=QUICK, q_start=path[0], footprints=around_best, merge_distance=0.0,
                           initialisations=HOLD)
    try:
        restricted = track(planar3, targets, options, guesses=guesses)
    except ValueError as error:
        assert "inside a scene element" in str(error)
    else:
        assert base_in_footprints(restricted.base, around_best) is None
        assert restricted.statistics.starts_rejected_in_footprints >= 1
    everywhere = np.array([[0.0, 0.0, 100.0, 100.0, 0.0]])
    with pytest.raises(ValueError, match="every one of the 4 solutions puts the robot base inside a scene element"):
        # 2 base guesses x the 2 default joint initialisations
        track(planar3, targets, TrackOptions(sqp=QUICK, q_start=path[0], footprints=everywhere), guesses=guesses)


def test_roll_symmetric_tool_tries_the_turned_targets():
    arm = make_robot("planar3", tool="hammer")
    assert arm.tool.roll_symmetric
    path = reachable_path(arm, 12)
    targets = targets_of(arm, path, np.zeros(3)).rotated_about_tool_z(np.pi)  # the other way round
    result = track(arm, targets, TrackOptions(sqp=QUICK, q_start=path[0], starts=2))
    assert result.statistics.roll_variant == 1
    # errors are measured against the chosen variant (the other one is pi away)
    assert np.median(result.rotation_error) < 0.3
