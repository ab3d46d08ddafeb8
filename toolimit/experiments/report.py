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


def markdown_table(cells: Sequence[CellResult]) -> str:
    """One row per experiment, one column per method: "goal reward (success rate)"; "-" where not measured."""
    lines = [
        "| tool | world | robot | demonstration | " + " | ".join(METHODS) + " |",
        "| --- | --- | --- | --- | " + " | ".join("---:" for _ in METHODS) + " |",
    ]
    for (tool, world, robot, demo), by_method in _groups(cells).items():
        values = [
            f"{by_method[m].goal_reward:.1f} ({by_method[m].success_rate:.2f})" if m in by_method else "-"
            for m in METHODS
        ]
        lines.append(f"| {tool} | {world} | {robot} | {demo} | " + " | ".join(values) + " |")
    return "\n".join(lines) + "\n"


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
