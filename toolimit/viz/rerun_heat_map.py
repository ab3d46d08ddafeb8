"""rerun recording of a goal-box heat map (:class:`toolimit.learn.heat_map.HeatMap`).

A 2D view seen from above, world x, y in metres, logged with y negated (rerun's 2D views point y
down) so that it reads like the SVG: ``heat_map/cells`` (one coloured box per grid point, labelled
with its goal reward, and "beyond reach" where the robot cannot reach the box; the colours of
:mod:`toolimit.viz.svg_heat_map`), ``heat_map/adr_range``,
``heat_map/deposit``, ``heat_map/reach`` (the tool's reach circle), ``heat_map/base`` and
``heat_map/aligned``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr

from toolimit.learn.heat_map import HeatMap
from toolimit.viz.rerun_file import recording_file
from toolimit.viz.svg_heat_map import INVALID, colour, scale_top

FLIP = np.array([1.0, -1.0])


def _rgb(hex_colour: str) -> tuple[int, int, int]:
    """(r, g, b) 0-255 of a ``#rrggbb`` colour (rerun takes numbers)."""
    return int(hex_colour[1:3], 16), int(hex_colour[3:5], 16), int(hex_colour[5:7], 16)


WHITE, BLACK, GREY = (255, 255, 255), (0, 0, 0), (68, 68, 68)


def save_heat_map_recording(heat_map: HeatMap, path: str | Path) -> Path | None:
    """Write ``heat_map`` to ``path`` (.rrd); None when rerun is disabled."""
    with recording_file(path, "toolimit_heat_map") as recording:
        if recording is None:
            return None
        xs, ys = heat_map.centres
        half = np.stack(np.meshgrid(np.diff(heat_map.x_edges), np.diff(heat_map.y_edges)), axis=-1).reshape(-1, 2) / 2
        centres = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
        values = heat_map.goal_rewards.reshape(-1)
        top = scale_top(values)
        recording.log(
            "heat_map/cells",
            rr.Boxes2D(
                centers=centres * FLIP,
                half_sizes=half,
                colors=[_rgb(INVALID if np.isnan(v) else colour(v / top)) for v in values],
                labels=[
                    ("no box" if np.isnan(v) else f"{v:.1f}") + ("" if reachable else " (beyond reach)")
                    for v, reachable in zip(values, heat_map.reachable.reshape(-1), strict=True)
                ],
            ),
        )
        low, high = heat_map.rectangle
        recording.log("heat_map/adr_range", rr.Boxes2D(mins=[low[0], -high[1]], sizes=high - low, colors=WHITE))
        cx, cy, half_length, half_width, yaw = heat_map.deposit
        corners = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1], [1, 1]]) * [half_length, half_width]
        rotation = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
        recording.log("heat_map/deposit", rr.LineStrips2D([(corners @ rotation.T + [cx, cy]) * FLIP], colors=GREY))
        angles = np.linspace(0.0, 2 * np.pi, 129)
        circle = heat_map.base + heat_map.reach * np.column_stack([np.cos(angles), np.sin(angles)])
        recording.log("heat_map/reach", rr.LineStrips2D([circle * FLIP], colors=BLACK))
        recording.log("heat_map/base", rr.Points2D([heat_map.base * FLIP], radii=0.02, colors=BLACK))
        recording.log("heat_map/aligned", rr.Points2D([heat_map.aligned * FLIP], radii=0.02, colors=WHITE))
    return Path(path)
