"""The differential-IK rollout that initialises the joints."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.trajopt import SqpOptions, TrackingProblem, TrackOptions, track
from toolimit.trajopt.initial_guess import ik_rollout

from trajopt_helpers import FPS, reachable_path, targets_of


def test_rollout_follows_a_slow_reachable_path(panda):
    path = reachable_path(panda, 20, speed=0.2)
    base = np.array([0.1, 0.2, 0.3])
    problem = TrackingProblem(panda, targets_of(panda, path, base), 1 / FPS, q_start=path[0])
    q = ik_rollout(problem, base)
    positions, _ = panda.tool_poses(q[1:], base)
    errors = np.linalg.norm(positions - problem.targets.positions, axis=1)
    assert q.shape == path.shape and np.array_equal(q[0], path[0])
    assert np.median(errors) < 5e-3, f"median error {np.median(errors):.4f} m"


def test_rollout_respects_the_limits(panda):
    path = reachable_path(panda, 20)
    path[10:, 0] += 2.0  # a jump no joint can follow
    path[:, 3] = np.linspace(path[0, 3], panda.upper[3] + 0.4, 21)
    problem = TrackingProblem(panda, targets_of(panda, path, np.zeros(3)), 1 / FPS, q_start=path[0])
    q = ik_rollout(problem, np.zeros(3))
    assert np.all(q >= panda.lower) and np.all(q <= panda.upper)
    assert np.all(np.abs(np.diff(q, axis=0)) <= panda.velocity_limit / FPS * (1 + 1e-12))


def test_track_runs_every_initialisation(planar3):
    path = reachable_path(planar3, 12)
    targets = targets_of(planar3, path, np.array([0.2, 0.0, 0.0]))
    options = TrackOptions(sqp=SqpOptions(max_iterations=10), starts=2, q_start=path[0],
                           initialisations=("hold", "rollout"), merge_distance=0.0)
    result = track(planar3, targets, options)
    assert len(result.statistics.start_costs) == 4
    assert result.statistics.initialisation in ("hold", "rollout")
    assert result.statistics.cost == min(result.statistics.start_costs)
    with pytest.raises(ValueError, match="initialisations"):
        TrackOptions(initialisations=("guess",))
