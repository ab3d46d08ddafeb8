"""Choosing how much to slow the demonstration down so that the robot can follow it.

A demonstration is often faster than a robot's joint velocity limits allow. Slowing it by a
factor S (dt = S / fps) trades duration for tracking accuracy; :func:`choose_time_scale` takes the
smallest S of a grid whose optimised trajectory has a median position error under a threshold.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from toolimit.robots import RobotModel
from toolimit.trajopt.problem import PoseTargets
from toolimit.trajopt.result import TimeScaleSearch, TrajectoryResult
from toolimit.trajopt.track import TrackOptions, track

#: Slow-down factors tried by ``--time-scale auto``, ascending.
TIME_SCALE_GRID = (1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0)
#: Median tool position error (m) under which a time scale is accepted.
MEDIAN_ERROR_THRESHOLD = 0.01


def choose_time_scale(
    robot: RobotModel,
    targets: PoseTargets,
    options: TrackOptions = TrackOptions(),
    grid: tuple[float, ...] = TIME_SCALE_GRID,
    threshold: float = MEDIAN_ERROR_THRESHOLD,
    rng: np.random.Generator | None = None,
) -> TrajectoryResult:
    """Track at each scale of ``grid`` in ascending order; return the first result whose median
    position error is below ``threshold`` (m), or the best-tracking one if none is.

    The returned result's ``statistics.time_scale_search`` holds the median error at each scale
    tried and whether the threshold was met.
    """
    if not grid:
        raise ValueError("the time-scale grid is empty")
    tried: dict[float, float] = {}
    best: TrajectoryResult | None = None
    for scale in sorted(grid):
        result = track(robot, targets, replace(options, time_scale=float(scale)), rng=rng)
        median = float(np.median(result.position_error))
        tried[float(scale)] = median
        if best is None or median < float(np.median(best.position_error)):
            best = result
        if median < threshold:
            best = result
            break
    assert best is not None and best.statistics is not None  # the grid is not empty; track records statistics
    met = float(np.median(best.position_error)) < threshold
    search = TimeScaleSearch(median_position_error_m=tried, threshold_m=threshold, threshold_met=met)
    return replace(best, statistics=replace(best.statistics, time_scale_search=search))
