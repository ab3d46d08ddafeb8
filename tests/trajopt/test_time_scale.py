"""Choosing the time scale: the smallest scale of the grid whose median position error is < 1 cm."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import toolimit.trajopt.time_scale as time_scale_module
from toolimit.trajopt import SqpOptions, TrackingWeights, TrackOptions, choose_time_scale
from toolimit.trajopt.result import TrackingStatistics

from trajopt_helpers import reachable_path, targets_of


def test_picks_the_smallest_scale_that_tracks_a_too_fast_demonstration(planar3):
    """A path at 1.6 times the velocity limits: real time cannot follow it, half speed can."""
    path = reachable_path(planar3, 24, amplitude=0.3, speed=0.8)
    fast = path[::2]  # the same motion in half the frames: twice the speed
    fast_velocity = np.abs(np.diff(fast, axis=0)).max(axis=0) * 24 / planar3.velocity_limit
    assert fast_velocity.max() > 1.5
    targets = targets_of(planar3, fast, np.array([0.1, 0.0, 0.0]))
    options = TrackOptions(weights=TrackingWeights(velocity=1e-6), sqp=SqpOptions(max_iterations=25), starts=2,
                           q_start=fast[0])
    result = choose_time_scale(planar3, targets, options, grid=(3.0, 1.0, 2.0))
    search = result.statistics.time_scale_search
    assert result.time_scale == 2.0
    assert list(search.median_position_error_m) == [1.0, 2.0], "stops at the first scale that tracks"
    assert search.median_position_error_m[1.0] > 0.01 > search.median_position_error_m[2.0]
    assert search.threshold_met
    assert result.dt == pytest.approx(2.0 / 24)


def test_returns_the_best_scale_when_none_meets_the_threshold(monkeypatch, planar3):
    medians = {1.0: 0.05, 1.5: 0.03, 2.0: 0.04}

    statistics = TrackingStatistics(
        cost=1.0, initial_cost=2.0, cost_terms={"total": 1.0}, iterations=1, qp_iterations=1, converged=True,
        start_index=0, roll_variant=0, initialisation="hold", start_costs=(1.0,), starts_rejected_in_footprints=0,
        starts_merged=0, wall_time_s=0.0, best_start_wall_time_s=0.0, weights=TrackingWeights(),
    )

    def fake_track(robot, targets, options, rng=None):
        return dataclasses.make_dataclass("R", ["position_error", "time_scale", "statistics"])(
            np.full(5, medians[options.time_scale]), options.time_scale, statistics)

    monkeypatch.setattr(time_scale_module, "track", fake_track)
    result = choose_time_scale(planar3, None, TrackOptions(), grid=(1.0, 1.5, 2.0))
    assert result.time_scale == 1.5
    assert not result.statistics.time_scale_search.threshold_met
    with pytest.raises(ValueError, match="empty"):
        choose_time_scale(planar3, None, TrackOptions(), grid=())
