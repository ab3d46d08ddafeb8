"""The results of ``toolimit reproduce``: ``results.json``, a markdown table and the figure (SVG).

``results.json`` holds the preset, ``seeds`` (those with cells), ``cells`` (each a
:class:`~toolimit.experiments.cells.CellResult` record with its ``seed``: ``tool``, ``demo``,
``robot``, ``method``, ``goal_reward``, ``success_rate``, ...), ``summary`` (each cell over its
seeds, :class:`~toolimit.experiments.summary.CellSummary`), ``aggregates`` (each method over its
demonstrations, :class:`~toolimit.experiments.summary.MethodSummary`) and ``claims`` (the paper's
claims read off them, :class:`~toolimit.experiments.claims.ClaimReading`). A ``results.json``
written before there were seeds (a ``preset`` with its ``seed``, cells without) reads as that one
seed's (:func:`read_results`). The first table has one row per experiment and one column per
method, "goal reward [95 % interval] (success [95 % interval])"; the second one row per method of
a tool, world and robot over its demonstrations; the third one row per claim and group. The figure
is the paper's: one group of bars per experiment, the goal reward on a log scale with its interval,
the success threshold drawn; one figure per tool, since the goal rewards of different tools do not
compare.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from toolimit.artifacts import save_json, save_text
from toolimit.experiments.cells import METHODS, CellResult
from toolimit.experiments.claims import ClaimReading, claims_table, read_claims
from toolimit.experiments.intervals import Interval
from toolimit.experiments.summary import METHOD, CellSummary, MethodSummary, Runs, summarise_cells, summarise_methods
from toolimit.viz.svg_chart import BarGroup, log_bar_chart_svg

RESULTS_JSON = "results.json"
RESULTS_MD = "results.md"
#: The goal reward at which the paper's success test can pass: the spade needs 10 spheres in the box
#: (for half of the episode), the hammer its nail in (1); the scythe's depends on the stalk count.
SUCCESS_GOAL_REWARD = {"spade": 10.0, "hammer": 1.0}


#: The table's columns after the methods': the final policy's steps past the robot's limits, its
#: export replayed open-loop.
EXTRA_COLUMNS = ("final: steps past limits", "exported (open-loop)")


def read_results(record: dict[str, Any]) -> tuple[dict[str, Any], dict[int, list[CellResult]]]:
    """The preset and the cells by seed of a ``results.json`` record, of either layout (module
    docstring)."""
    runs: dict[int, list[CellResult]] = {}
    for entry in record["cells"]:
        fields = dict(entry)
        seed = fields.pop("seed") if "seed" in fields else record["preset"]["seed"]
        runs.setdefault(int(seed), []).append(CellResult(**fields))
    return record["preset"], runs


def markdown_table(summaries: Sequence[CellSummary], seeds: Sequence[int]) -> str:
    """One row per experiment, one column per method: "goal reward [interval] (success
    [interval])", with the number of seeds where fewer than ``seeds`` measured it; then the final
    policy's share of steps past the robot's limits (largest velocity and acceleration ratios) and
    its export replayed open-loop; "-" where not measured."""
    columns = (*METHODS, *EXTRA_COLUMNS)
    lines = [
        "| tool | world | robot | demonstration | " + " | ".join(columns) + " |",
        "| --- | --- | --- | --- | " + " | ".join("---:" for _ in columns) + " |",
    ]
    for experiment, by_method in _by_experiment(summaries).items():
        values = [_cell(by_method[m], len(seeds)) if m in by_method else "-" for m in METHODS]
        final = by_method.get(METHOD)
        values += [_limits(final), _exported(final, len(seeds))]
        lines.append("| " + " | ".join(experiment) + " | " + " | ".join(values) + " |")
    return "\n".join(lines) + "\n"


def aggregates_table(aggregates: Sequence[MethodSummary]) -> str:
    """One row per method of a tool, world and robot: its demonstrations and runs, the
    interquartile mean of the runs' success rates and P(final > method), each with its interval."""
    lines = [
        "| tool | world | robot | method | demonstrations | runs | success (IQM) | P(final > method) |",
        "| --- | --- | --- | --- | ---: | ---: | ---: | ---: |",
    ]
    for a in aggregates:
        improvement = "-" if a.improvement is None else f"{_interval(a.improvement, 2)} on {len(a.improvement_demos)}"
        row = (a.tool, a.world, a.robot, a.method, str(len(a.demos)), str(a.runs), _interval(a.success_iqm, 2))
        lines.append("| " + " | ".join(row) + f" | {improvement} |")
    return "\n".join(lines) + "\n"


def _interval(interval: Interval, digits: int) -> str:
    """ "value [low, high]", or "value [-]" with no interval."""
    if interval.low is None or interval.high is None:
        return f"{interval.value:.{digits}f} [-]"
    return f"{interval.value:.{digits}f} [{interval.low:.{digits}f}, {interval.high:.{digits}f}]"


def _outcome(goal_reward: Interval, success: Interval) -> str:
    return f"{_interval(goal_reward, 1)} ({_interval(success, 2)})"


def _cell(summary: CellSummary, seeds: int) -> str:
    return _outcome(summary.goal_reward, summary.success) + _fewer(summary.seeds, seeds)


def _fewer(measured: Sequence[int], seeds: int) -> str:
    """ ", k of n seeds" when fewer than the figure's ``seeds`` measured a column, else ""."""
    return f", {len(measured)} of {seeds} seeds" if len(measured) < seeds else ""


def _limits(final: CellSummary | None) -> str:
    """ "share [interval] (velocity ratio, acceleration ratio)", e.g. "0.00 [0.00, 0.00] (0.95, 0.95)";
    "-" when not recorded."""
    if final is None or final.steps_past_limits is None or final.max_velocity_ratio is None:
        return "-"
    acceleration = final.max_acceleration_ratio
    ratios = f"{final.max_velocity_ratio:.2f}" + ("" if acceleration is None else f", {acceleration:.2f}")
    return f"{_interval(final.steps_past_limits, 2)} ({ratios})"


def _exported(final: CellSummary | None, seeds: int) -> str:
    """The export's open-loop outcome with the number of seeds where fewer than ``seeds`` replayed
    it, "-" with no export."""
    if final is None or final.exported_goal_reward is None or final.exported_success is None:
        return "-"
    return _outcome(final.exported_goal_reward, final.exported_success) + _fewer(final.exported_seeds, seeds)


def _by_experiment(summaries: Sequence[CellSummary]) -> dict[tuple[str, str, str, str], dict[str, CellSummary]]:
    """Summaries by experiment (tool, world, robot, demo), then by method."""
    groups: dict[tuple[str, str, str, str], dict[str, CellSummary]] = {}
    for summary in summaries:
        groups.setdefault(summary.experiment, {})[summary.method] = summary
    return groups


def results_markdown(
    summaries: Sequence[CellSummary],
    aggregates: Sequence[MethodSummary],
    claims: Sequence[ClaimReading],
    seeds: Sequence[int],
) -> str:
    """``results.md``: the three tables, with how to read them."""
    over = f"seed{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))}" if seeds else "no seed yet"
    return (
        f"# Results over {over}\n\n"
        "Goal reward (success rate) per method: the mean over seeds of each seed's mean over its "
        "episodes, with its 95 % bootstrap interval over seeds and episodes "
        "(`toolimit.experiments.intervals`).\n\n"
        + markdown_table(summaries, seeds)
        + "\nEach method over its demonstrations: the interquartile mean of the runs' success rates (a run: "
        "one seed on one demonstration) with its stratified bootstrap interval, and the probability that "
        "the final policy beats the method on a demonstration, on the demonstrations both were measured on; "
        "[-]: one run per demonstration, no interval.\n\n"
        + aggregates_table(aggregates)
        + "\nThe paper's claims, read off these intervals (`toolimit.experiments.claims`): how many items "
        "meet each claim's test on their whole interval, on their mean and anywhere within their interval; "
        "a claim holds when enough meet it on their whole interval. Few seeds make the intervals too narrow.\n\n"
        + claims_table(claims)
    )


def write_results(out_dir: Path, runs: Runs, preset: dict[str, Any]) -> list[Path]:
    """Write ``results.json``, ``results.md`` and ``results_<tool>.svg`` of the cells ``runs``
    (seed -> cells) into ``out_dir``; the paths."""
    seeds = sorted(seed for seed, cells in runs.items() if cells)
    summaries, aggregates = summarise_cells(runs), summarise_methods(runs)
    claims = read_claims(summaries, aggregates)
    record = {
        "preset": preset,
        "seeds": seeds,
        "cells": [cell.record() | {"seed": seed} for seed in seeds for cell in runs[seed]],
        "summary": [summary.record() for summary in summaries],
        "aggregates": [aggregate.record() for aggregate in aggregates],
        "claims": [claim.record() for claim in claims],
    }
    save_json(out_dir / RESULTS_JSON, record)
    written = [
        out_dir / RESULTS_JSON,
        save_text(out_dir / RESULTS_MD, results_markdown(summaries, aggregates, claims, seeds)),
    ]
    groups = _by_experiment(summaries)
    for tool in dict.fromkeys(summary.tool for summary in summaries):
        bars = [
            BarGroup(
                f"{demo} ({robot}, {world})",
                [by[m].goal_reward.value if m in by else None for m in METHODS],
                [_span(by[m].goal_reward) if m in by else None for m in METHODS],
            )
            for (t, world, robot, demo), by in groups.items()
            if t == tool
        ]
        svg = log_bar_chart_svg(
            bars,
            METHODS,
            title=f"{tool}: goal reward per method" + (f", {len(seeds)} seeds" if len(seeds) > 1 else ""),
            y_label="goal reward",
            threshold=SUCCESS_GOAL_REWARD.get(tool),
        )
        written.append(save_text(out_dir / f"results_{tool}.svg", svg))
    return written


def _span(interval: Interval) -> tuple[float, float] | None:
    """The chart's whisker of ``interval``: (low, high), or None with no interval."""
    return None if interval.low is None or interval.high is None else (interval.low, interval.high)
