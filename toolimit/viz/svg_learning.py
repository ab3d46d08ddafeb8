"""Learning curves (``curve.jsonl`` of :mod:`toolimit.learn.training`) as an SVG line plot.

One line with markers per run (one marker per PPO update), x = PPO environment steps, y = one
quantity of the episodes PPO collected (so of the stochastic policy): the success rate, the goal
reward, the return, the action standard deviation or the update's KL.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path

from toolimit.viz.svg_plot import Series, line_plot_svg

#: Key of ``curve.jsonl`` -> axis label.
METRICS = {
    "success_rate": "success rate of the collected episodes",
    "goal_reward_mean": "goal reward (mean of the collected episodes)",
    "return_mean": "episode return (mean)",
    "action_std_mean": "action standard deviation (normalised)",
    "approx_kl": "KL of the update",
}


def learning_curve_svg(
    curves: Mapping[str, str | os.PathLike[str]], metric: str = "success_rate", title: str | None = None
) -> str:
    """The SVG text of ``metric`` against PPO env steps for each run: ``curves`` maps a run's
    label to its ``curve.jsonl``. The axis of the success rate spans [0, 1], that of the goal reward
    starts at 0."""
    if metric not in METRICS:
        raise ValueError(f"unknown metric {metric!r}; choose one of {', '.join(METRICS)}")
    series, top = [], 1.0
    for label, path in curves.items():
        records = [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]
        if not records:
            raise ValueError(f"{path}: no update recorded")
        steps = [float(record["env_steps"]) for record in records]
        values = [float(record[metric]) for record in records]
        series.append(Series(label, steps, values, markers=True))
        top = max([top, *values])
    counts = metric in ("success_rate", "goal_reward_mean")  # never negative: the axis starts at 0
    return line_plot_svg(
        series,
        title or METRICS[metric],
        "PPO environment steps",
        METRICS[metric],
        y_range=(-0.05 * top, 1.05 * top) if counts else None,
    )
