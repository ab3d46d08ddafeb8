"""The figure over training seeds: each cell's intervals and each method's aggregate.

A reproduction with several seeds has, for each seed, its own cells
(:class:`~toolimit.experiments.cells.CellResult`); :func:`summarise_cells` gives each (experiment,
method) over the seeds that measured it: the mean goal reward and success with their intervals over
seeds and episodes, the final policy's share of steps past the robot's limits and its exported
open-loop replay (:mod:`toolimit.experiments.intervals`). :func:`summarise_methods` gives each
method of a tool, world and robot over its demonstrations: the interquartile mean of the runs'
success rates (a run: one seed on one demonstration) and the probability that the method's final
policy beats it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from toolimit.experiments.cells import METHODS, CellResult, successes_from_rate
from toolimit.experiments.intervals import (
    Interval,
    interquartile_mean,
    probability_of_improvement,
    seed_episode_interval,
)

#: Seed -> that seed's cells.
Runs = Mapping[int, Sequence[CellResult]]
#: The method the others are compared with.
METHOD = "final"


@dataclass(frozen=True)
class CellSummary:
    """One (experiment, method) over the seeds that measured it.

    Attributes:
        tool, world, robot, demo, method: what was measured.
        seeds: the seeds with this cell.
        episodes: evaluation episodes per seed.
        goal_reward, success: mean over seeds of each seed's mean over its episodes, 95 % interval.
        steps_past_limits: a learnt policy's share of steps past the robot's limits, 95 % interval
            (None: not a learnt policy, or no seed recorded it).
        max_velocity_ratio, max_acceleration_ratio: the largest over seeds and episodes (None: not
            recorded, or the robot publishes no acceleration limit).
        exported_goal_reward, exported_success: the final policy's export replayed open-loop, 95 %
            interval (None: no export).
        exported_seeds: the seeds whose export was replayed.
        wall_time_s: the seeds' wall times added up.
    """

    tool: str
    world: str
    robot: str
    demo: str
    method: str
    seeds: list[int]
    episodes: int
    goal_reward: Interval
    success: Interval
    steps_past_limits: Interval | None
    max_velocity_ratio: float | None
    max_acceleration_ratio: float | None
    exported_goal_reward: Interval | None
    exported_success: Interval | None
    exported_seeds: list[int]
    wall_time_s: float

    @property
    def experiment(self) -> tuple[str, str, str, str]:
        """(tool, world, robot, demo): the figure's group."""
        return self.tool, self.world, self.robot, self.demo

    def record(self) -> dict[str, Any]:
        """JSON-ready form (the ``summary`` entries of ``results.json``)."""
        return _record(self)


@dataclass(frozen=True)
class MethodSummary:
    """One method of a tool, world and robot over its demonstrations and seeds.

    Attributes:
        tool, world, robot, method: what is aggregated.
        demos: the demonstrations it was measured on.
        runs: (seed, demonstration) pairs measured.
        success_iqm: interquartile mean of the runs' success rates, stratified 95 % interval.
        improvement: P(final > this method) on the demonstrations both were measured on, 95 %
            interval (None for the final policy itself, or with no demonstration in common).
        improvement_demos: those demonstrations.
    """

    tool: str
    world: str
    robot: str
    method: str
    demos: list[str]
    runs: int
    success_iqm: Interval
    improvement: Interval | None
    improvement_demos: list[str]

    def record(self) -> dict[str, Any]:
        """JSON-ready form (the ``aggregates`` entries of ``results.json``)."""
        return _record(self)


def _record(summary: CellSummary | MethodSummary) -> dict[str, Any]:
    """A summary's fields, each interval as its record."""
    return {key: value.record() if isinstance(value, Interval) else value for key, value in vars(summary).items()}


def _by_cell(runs: Runs) -> dict[tuple[str, str, str, str, str], dict[int, CellResult]]:
    """Cells by (tool, world, robot, demo, method), then by seed; groups in the order first met,
    seeds ascending."""
    found: dict[tuple[str, str, str, str, str], dict[int, CellResult]] = {}
    for seed in sorted(runs):
        for cell in runs[seed]:
            found.setdefault((cell.tool, cell.world, cell.robot, cell.demo, cell.method), {})[seed] = cell
    return found


def summarise_cells(runs: Runs) -> list[CellSummary]:
    """Every measured (experiment, method) over its seeds, grouped by experiment, methods in the
    figure's order."""
    by_cell = _by_cell(runs)
    experiments = list(dict.fromkeys(key[:4] for key in by_cell))
    return [
        _summarise(experiment, method, by_cell[experiment + (method,)])
        for experiment in experiments
        for method in METHODS
        if experiment + (method,) in by_cell
    ]


def _summarise(experiment: tuple[str, str, str, str], method: str, by_seed: dict[int, CellResult]) -> CellSummary:
    cells = list(by_seed.values())
    limits = [cell.limits for cell in cells if cell.limits is not None]
    exported = [cell.exported for cell in cells if cell.exported is not None]
    accelerations = [record["max_acceleration_ratio"] for record in limits]
    return CellSummary(
        *experiment,
        method,
        seeds=list(by_seed),
        episodes=len(cells[0].goal_rewards),
        goal_reward=seed_episode_interval([cell.goal_rewards for cell in cells]),
        success=seed_episode_interval([cell.episode_successes() for cell in cells]),
        steps_past_limits=seed_episode_interval([r["share_of_steps_past_limits_per_episode"] for r in limits])
        if limits
        else None,
        max_velocity_ratio=max(r["max_velocity_ratio"] for r in limits) if limits else None,
        max_acceleration_ratio=None if not limits or None in accelerations else max(accelerations),
        exported_goal_reward=seed_episode_interval([r["goal_reward"] for r in exported]) if exported else None,
        exported_success=seed_episode_interval([_exported_successes(r) for r in exported]) if exported else None,
        exported_seeds=[seed for seed, cell in by_seed.items() if cell.exported is not None],
        wall_time_s=sum(cell.wall_time_s for cell in cells),
    )


def _exported_successes(record: dict[str, Any]) -> np.ndarray:
    """(E,) bool of an export's open-loop replay; rebuilt from its success rate in a record saved
    before the replay kept them."""
    if "successes" in record:
        return np.asarray(record["successes"], dtype=bool)
    return successes_from_rate(record["success_rate"], record["episodes"])


def summarise_methods(runs: Runs) -> list[MethodSummary]:
    """Every method of every (tool, world, robot) over its demonstrations: the interquartile mean
    of the runs' success rates and P(final > method), in the order first met."""
    scores: dict[tuple[str, str, str], dict[str, dict[str, list[float]]]] = {}  # group -> method -> demo -> runs
    for (tool, world, robot, demo, method), by_seed in _by_cell(runs).items():
        by_demo = scores.setdefault((tool, world, robot), {}).setdefault(method, {})
        by_demo[demo] = [cell.success_rate for cell in by_seed.values()]
    summaries = []
    for group, by_method in scores.items():
        final = by_method.get(METHOD, {})
        for method in [m for m in METHODS if m in by_method]:
            by_demo = by_method[method]
            common = [demo for demo in by_demo if demo in final] if method != METHOD else []
            improvement = (
                probability_of_improvement([final[d] for d in common], [by_demo[d] for d in common]) if common else None
            )
            summaries.append(
                MethodSummary(
                    *group,
                    method,
                    demos=list(by_demo),
                    runs=sum(len(values) for values in by_demo.values()),
                    success_iqm=interquartile_mean(list(by_demo.values())),
                    improvement=improvement,
                    improvement_demos=common,
                )
            )
    return summaries
