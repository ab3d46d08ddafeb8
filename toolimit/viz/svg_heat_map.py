"""A heat map of goal reward over goal box positions as a standalone SVG file, without matplotlib.

Seen from above: world x to the right, y up, equal scale on both axes (metres). One coloured cell
per grid point (:class:`toolimit.learn.heat_map.HeatMap`; hover shows its box position and value),
grey where the box cannot stand, struck through where the robot cannot reach the box; a colour bar
with its scale; the ADR rectangle (dashed), the aligned box position (white cross), the deposit
(grey outline), the robot base (black dot) and the tool's reach around it (black circle), all
clipped to the map.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING
from xml.sax.saxutils import escape

import numpy as np

if TYPE_CHECKING:
    from toolimit.learn.heat_map import HeatMap

#: The colour scale (viridis, sampled at 0, 0.25, 0.5, 0.75, 1), interpolated linearly in RGB.
VIRIDIS = np.array([[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]], dtype=float)
#: Fill of cells where the box cannot stand.
INVALID = "#bdbdbd"
#: Size of the map's longer side (px) and the margins around it (px).
MAP_SIZE = 520
MARGIN = 60
LEGEND_WIDTH = 170  # the colour bar, its ticks and its title


def colour(fraction: float) -> str:
    """The hex colour of ``fraction`` in [0, 1] of the scale (clipped)."""
    position = float(np.clip(fraction, 0.0, 1.0)) * (len(VIRIDIS) - 1)
    low = min(int(position), len(VIRIDIS) - 2)
    rgb = VIRIDIS[low] + (position - low) * (VIRIDIS[low + 1] - VIRIDIS[low])
    return "#" + "".join(f"{round(c):02x}" for c in rgb)


def scale_top(values: np.ndarray) -> float:
    """The colour scale's top: the largest finite value, at least 1."""
    finite = values[np.isfinite(values)]
    return max(1.0, float(finite.max()) if finite.size else 1.0)


def heat_map_svg(heat_map: HeatMap, title: str, value_label: str = "spheres in the box at the end") -> str:
    """The SVG text of ``heat_map``'s goal rewards (module docstring)."""
    x0, x1 = float(heat_map.x_edges[0]), float(heat_map.x_edges[-1])
    y0, y1 = float(heat_map.y_edges[0]), float(heat_map.y_edges[-1])
    scale = MAP_SIZE / max(x1 - x0, y1 - y0)  # px per m
    width, height = (x1 - x0) * scale, (y1 - y0) * scale

    def px(x: float, y: float) -> tuple[float, float]:
        return MARGIN + (x - x0) * scale, MARGIN + (y1 - y) * scale

    top = scale_top(heat_map.goal_rewards)
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{2 * MARGIN + width + LEGEND_WIDTH:.0f}" '
        f'height="{2 * MARGIN + height:.0f}" font-family="sans-serif" font-size="12">',
        f"<title>{escape(title)}</title>",
        f'<text x="{MARGIN}" y="{MARGIN / 2:.0f}" font-size="15">{escape(title)}</text>',
        f'<clipPath id="map"><rect x="{MARGIN}" y="{MARGIN}" width="{width:.2f}" height="{height:.2f}"/></clipPath>',
    ]
    xs, ys = heat_map.centres
    for j, y in enumerate(ys):
        for i, x in enumerate(xs):
            value = heat_map.goal_rewards[j, i]
            left, upper = px(heat_map.x_edges[i], heat_map.y_edges[j + 1])
            fill = INVALID if np.isnan(value) else colour(value / top)
            text = "box cannot stand here" if np.isnan(value) else f"{value:.1f} {value_label}"
            text += "" if heat_map.reachable[j, i] else " (beyond the robot's reach)"
            cell_width = (heat_map.x_edges[i + 1] - heat_map.x_edges[i]) * scale
            cell_height = (heat_map.y_edges[j + 1] - heat_map.y_edges[j]) * scale
            parts.append(
                f'<rect class="cell" x="{left:.2f}" y="{upper:.2f}" width="{cell_width:.2f}" '
                f'height="{cell_height:.2f}" fill="{fill}">'
                f"<title>box at x = {x:.2f} m, y = {y:.2f} m: {escape(text)}</title></rect>"
            )
            if not heat_map.reachable[j, i]:
                parts.append(
                    f'<path class="unreachable" d="M {left:.2f} {upper + cell_height:.2f} L {left + cell_width:.2f} '
                    f'{upper:.2f}" stroke="white" stroke-width="1.5" opacity="0.7"/>'
                )
    parts += _marks(heat_map, px, scale)
    parts += _axes(x0, x1, y0, y1, px, width, height)
    parts += _legend(top, MARGIN + width + 25, height, value_label)
    parts.append("</svg>")
    return "\n".join(parts) + "\n"


def _marks(heat_map: HeatMap, px, scale: float) -> list[str]:  # type: ignore[no-untyped-def]
    """The rectangle, deposit, reach circle, base and aligned position, clipped to the map."""
    (rx0, ry0), (rx1, ry1) = heat_map.rectangle
    left, upper = px(rx0, ry1)
    cx, cy, half_length, half_width, yaw = heat_map.deposit
    dx, dy = px(cx, cy)
    bx, by = px(*heat_map.base)
    ax, ay = px(*heat_map.aligned)
    return [
        '<g clip-path="url(#map)" fill="none">',
        f'<rect x="{left:.2f}" y="{upper:.2f}" width="{(rx1 - rx0) * scale:.2f}" height="{(ry1 - ry0) * scale:.2f}" '
        'stroke="white" stroke-width="2" stroke-dasharray="8 5"><title>ADR range (100 x 90 cm)</title></rect>',
        f'<rect x="{dx - half_length * scale:.2f}" y="{dy - half_width * scale:.2f}" width="{2 * half_length * scale:.2f}" '
        f'height="{2 * half_width * scale:.2f}" transform="rotate({-math.degrees(yaw):.2f} {dx:.2f} {dy:.2f})" '
        'stroke="#444444" stroke-width="2"><title>sand deposit</title></rect>',
        f'<circle cx="{bx:.2f}" cy="{by:.2f}" r="{heat_map.reach * scale:.2f}" stroke="black" stroke-width="2">'
        f"<title>tool reach {heat_map.reach:.2f} m</title></circle>",
        f'<circle cx="{bx:.2f}" cy="{by:.2f}" r="5" fill="black"><title>robot base</title></circle>',
        f'<path d="M {ax - 8:.2f} {ay - 8:.2f} L {ax + 8:.2f} {ay + 8:.2f} M {ax - 8:.2f} {ay + 8:.2f} L {ax + 8:.2f} '
        f'{ay - 8:.2f}" stroke="white" stroke-width="3"><title>aligned box position</title></path>',
        "</g>",
    ]


def _axes(x0: float, x1: float, y0: float, y1: float, px, width: float, height: float) -> list[str]:  # type: ignore[no-untyped-def]
    """Frame, ticks every 0.25 m and axis labels."""
    parts = [f'<rect x="{MARGIN}" y="{MARGIN}" width="{width:.2f}" height="{height:.2f}" fill="none" stroke="black"/>']
    for value in np.arange(math.ceil(x0 / 0.25) * 0.25, x1 + 1e-9, 0.25):
        x, _ = px(value, y0)
        parts.append(f'<text x="{x:.2f}" y="{MARGIN + height + 16:.2f}" text-anchor="middle">{value:.2f}</text>')
    for value in np.arange(math.ceil(y0 / 0.25) * 0.25, y1 + 1e-9, 0.25):
        _, y = px(x0, value)
        parts.append(f'<text x="{MARGIN - 6}" y="{y + 4:.2f}" text-anchor="end">{value:.2f}</text>')
    parts.append(
        f'<text x="{MARGIN + width / 2:.2f}" y="{MARGIN + height + 36:.2f}" text-anchor="middle">box x (m)</text>'
    )
    parts.append(
        f'<text x="{MARGIN - 45}" y="{MARGIN + height / 2:.2f}" text-anchor="middle" '
        f'transform="rotate(-90 {MARGIN - 45} {MARGIN + height / 2:.2f})">box y (m)</text>'
    )
    return parts


def _legend(top: float, x: float, height: float, label: str) -> list[str]:
    """A vertical colour bar from 0 (bottom) to ``top`` with five ticks, the grey 'invalid' key and
    the stroke marking cells beyond reach."""
    bar = min(height, 300.0)
    stops = "".join(
        f'<stop offset="{k / (len(VIRIDIS) - 1):.2f}" stop-color="{colour(1 - k / (len(VIRIDIS) - 1))}"/>'
        for k in range(len(VIRIDIS))
    )
    parts = [
        f'<linearGradient id="scale" x1="0" y1="0" x2="0" y2="1">{stops}</linearGradient>',
        f'<rect x="{x:.2f}" y="{MARGIN}" width="18" height="{bar:.2f}" fill="url(#scale)" stroke="black"/>',
        f'<text x="{x:.2f}" y="{MARGIN - 8}">{escape(label)}</text>',
    ]
    for k in range(5):
        value = top * k / 4
        y = MARGIN + bar * (1 - k / 4)
        parts.append(f'<text x="{x + 24:.2f}" y="{y + 4:.2f}">{value:.1f}</text>')
    parts.append(f'<rect x="{x:.2f}" y="{MARGIN + bar + 14:.2f}" width="18" height="12" fill="{INVALID}"/>')
    parts.append(f'<text x="{x + 24:.2f}" y="{MARGIN + bar + 24:.2f}">no box</text>')
    parts.append(
        f'<path d="M {x:.2f} {MARGIN + bar + 52:.2f} L {x + 18:.2f} {MARGIN + bar + 40:.2f}" stroke="black" stroke-width="1.5"/>'
    )
    parts.append(f'<text x="{x + 24:.2f}" y="{MARGIN + bar + 50:.2f}">beyond reach</text>')
    return parts
