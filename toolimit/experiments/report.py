"""The results of ``toolimit reproduce``: ``results.json``, a markdown table and the figure (SVG).

``results.json`` holds ``cells`` (each a :class:`~toolimit.experiments.cells.CellResult` record:
``tool``, ``demo``, ``robot``, ``method``, ``goal_reward``, ``success_rate``, ...) and the preset.
The table has one row per experiment and one column per method, "goal reward (success rate)". The
figure is the paper's: one group of bars per experiment, the goal reward on a log scale, the success
threshold drawn; one figure per tool, since the goal rewards of different tools do not compare.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from toolimit.artifacts import save_json, save_text
from toolimit.experiments.cells import METHODS, CellResult
from toolimit.viz.svg_chart import BarGroup, log_bar_chart_svg

RESULTS_JSON = "results.json"
RESULTS_MD = "results.md"
#: The goal reward at which the paper's success test can pass: the spade needs 10 spheres in the box
#: (for half of the episode), the hammer its nail in (1); the scythe's depends on the stalk count.
SUCCESS_GOAL_REWARD = {"spade": 10.0, "hammer": 1.0}


def _groups(cells: Sequence[CellResult]) -> dict[tuple[str, str, str, str], dict[str, CellResult]]:
    """Cells by (tool, world, robot, demo), then by method, in the order first met."""
    groups: dict[tuple[str, str, str, str], dict[str, CellResult]] = {}
    for cell in cells:
        groups.setdefault((cell.tool, cell.world, cell.robot, cell.demo), {})[cell.method] = cell
    return groups


#: The table's columns after the methods': the final policy's steps past the robot's limits, its
#: export replayed open-loop.
EXTRA_COLUMNS = ("final: steps past limits", "exported (open-loop)")


def markdown_table(cells: Sequence[CellResult]) -> str:
    """One row per experiment, one column per method: "goal reward (success rate)", then the final
    policy's share of steps past the robot's limits (largest velocity and acceleration ratios) and
    its export replayed open-loop; "-" where not measured."""
    lines = [
        "| tool | world | robot | demonstration | " + " | ".join((*METHODS, *EXTRA_COLUMNS)) + " |",
        "| --- | --- | --- | --- | " + " | ".join("---:" for _ in (*METHODS, *EXTRA_COLUMNS)) + " |",
    ]
    for (tool, world, robot, demo), by_method in _groups(cells).items():
        values = [
            _outcome(by_method[m].goal_reward, by_method[m].success_rate) if m in by_method else "-" for m in METHODS
        ]
        final = by_method.get("final")
        values.append(_limits(final.limits) if final is not None and final.limits is not None else "-")
        exported = None if final is None else final.exported
        values.append(_outcome(exported["goal_reward_mean"], exported["success_rate"]) if exported else "-")
        lines.append(f"| {tool} | {world} | {robot} | {demo} | " + " | ".join(values) + " |")
    return "\n".join(lines) + "\n"


def _outcome(goal_reward: float, success_rate: float) -> str:
    return f"{goal_reward:.1f} ({success_rate:.2f})"


def _limits(record: dict[str, Any]) -> str:
    """ "share (velocity ratio, acceleration ratio)", e.g. "0.00 (0.95, 0.95)"."""
    acceleration = record["max_acceleration_ratio"]
    ratios = f"{record['max_velocity_ratio']:.2f}" + ("" if acceleration is None else f", {acceleration:.2f}")
    return f"{record['share_of_steps_past_limits']:.2f} ({ratios})"


def write_results(out_dir: Path, cells: Sequence[CellResult], preset: dict[str, Any]) -> list[Path]:
    """Write ``results.json``, ``results.md`` and ``results_<tool>.svg`` into ``out_dir``; the paths."""
    save_json(out_dir / RESULTS_JSON, {"preset": preset, "cells": [c.record() for c in cells]})
    title = "# Results: goal reward (success rate) per method\n\n"
    written = [out_dir / RESULTS_JSON, save_text(out_dir / RESULTS_MD, title + markdown_table(cells))]
    for tool in dict.fromkeys(cell.tool for cell in cells):
        groups = [
            BarGroup(f"{demo} ({robot}, {world})", [by[m].goal_reward if m in by else None for m in METHODS])
            for (t, world, robot, demo), by in _groups(cells).items()
            if t == tool
        ]
        svg = log_bar_chart_svg(
            groups,
            METHODS,
            title=f"{tool}: goal reward per method",
            y_label="goal reward",
            threshold=SUCCESS_GOAL_REWARD.get(tool),
        )
        written.append(save_text(out_dir / f"results_{tool}.svg", svg))
    return written
