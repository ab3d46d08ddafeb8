"""A line and marker plot of several series as SVG text, written without matplotlib.

For the notebooks' inline figures (``IPython.display.SVG(text)``) and files a browser opens: each
series is a polyline (a non-finite value breaks it), markers (hover shows the series' label and
the point's values), or both; axes with round ticks and labels, a legend below. ``log_y`` puts the
y axis on a log10 scale (values <= 0 are left out); ``equal_aspect`` gives both axes the same scale
(for pictures of a scene: metres on both axes).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass
from xml.sax.saxutils import escape

import numpy as np

from toolimit.viz.svg_chart import PALETTE

#: Margins around the plotting area, px: left (tick labels, y label), right, top (title), bottom (x label).
LEFT, RIGHT, TOP, BOTTOM = 70.0, 20.0, 36.0, 48.0
#: Height of one legend row, px.
LEGEND_ROW = 18.0


@dataclass(frozen=True)
class Series:
    """One series of a plot.

    Attributes:
        label: its name in the legend.
        x, y: (N,) coordinates in the axes' units; a non-finite value breaks the line there.
        line: draw a polyline through the points. markers: draw a circle at each point.
        colour: an SVG colour; None takes the palette's next one.
        dashed: a dashed line.
    """

    label: str
    x: Sequence[float] | np.ndarray
    y: Sequence[float] | np.ndarray
    line: bool = True
    markers: bool = False
    colour: str | None = None
    dashed: bool = False


def nice_ticks(low: float, high: float, count: int = 5) -> list[float]:
    """About ``count`` round tick values (1, 2 or 5 times a power of ten apart) within [low, high]."""
    if not high > low:
        return [low]
    raw = (high - low) / max(count, 1)
    power = 10.0 ** math.floor(math.log10(raw))
    step = min((m * power for m in (1, 2, 5, 10)), key=lambda step: abs((high - low) / step - count))
    first = math.ceil(low / step - 1e-9)
    return [round(k * step, 12) for k in range(first, math.floor(high / step + 1e-9) + 1)]


def outline(footprint: Sequence[float] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(5,) x and y of the closed outline of a ground rectangle (centre x, centre y, half-length
    along its own x, half-width, yaw; m, rad), as the scenes' ``footprints`` give them."""
    cx, cy, half_length, half_width, yaw = (float(v) for v in footprint)
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]]) * [half_length, half_width]
    c, s = math.cos(yaw), math.sin(yaw)
    return cx + c * corners[:, 0] - s * corners[:, 1], cy + s * corners[:, 0] + c * corners[:, 1]


def line_plot_svg(
    series: Sequence[Series],
    title: str,
    x_label: str,
    y_label: str,
    width: float = 640.0,
    height: float = 360.0,
    log_y: bool = False,
    equal_aspect: bool = False,
    x_range: tuple[float, float] | None = None,
    y_range: tuple[float, float] | None = None,
) -> str:
    """The SVG text of ``series`` on shared axes; ``width`` x ``height`` px is the plotting area
    with its margins (the legend adds rows below). Ranges default to the data's, padded by 5 %."""
    if not series:
        raise ValueError("a plot needs at least one series")
    points = []
    for s in series:
        x, y = np.asarray(s.x, dtype=float), np.asarray(s.y, dtype=float)
        if x.shape != y.shape or x.ndim != 1:
            raise ValueError(f"series {s.label!r}: x and y must be 1-D of one length, got {x.shape} and {y.shape}")
        if log_y:
            y = np.where(y > 0, y, np.nan)
        points.append((x, np.log10(y) if log_y else y))
    xs = np.concatenate([x[np.isfinite(x) & np.isfinite(y)] for x, y in points])
    ys = np.concatenate([y[np.isfinite(x) & np.isfinite(y)] for x, y in points])
    if not xs.size:
        raise ValueError("no finite point to plot")
    x0, x1 = x_range if x_range is not None else _padded(float(xs.min()), float(xs.max()))
    if y_range is not None:
        y0, y1 = (math.log10(v) for v in y_range) if log_y else y_range
    else:
        y0, y1 = _padded(float(ys.min()), float(ys.max()))
    plot_w, plot_h = width - LEFT - RIGHT, height - TOP - BOTTOM
    if equal_aspect:
        scale = min(plot_w / (x1 - x0), plot_h / (y1 - y0))
        plot_w, plot_h = scale * (x1 - x0), scale * (y1 - y0)

    def px(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return LEFT + (x - x0) / (x1 - x0) * plot_w, TOP + (y1 - y) / (y1 - y0) * plot_h

    total_w, legend_y = LEFT + plot_w + RIGHT, TOP + plot_h + BOTTOM
    # Several figures inline in one page share one id space: the clip path's id is the figure's own.
    clip = "plot-" + hashlib.sha1(repr((title, [s.label for s in series], x0, x1, y0, y1)).encode()).hexdigest()[:10]
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{total_w:.0f}" '
        f'height="{legend_y + LEGEND_ROW * len(series) + 4:.0f}" font-family="sans-serif" font-size="11">',
        f"<title>{escape(title)}</title>",
        f'<text x="{total_w / 2:.1f}" y="20" text-anchor="middle" font-size="14">{escape(title)}</text>',
        f'<clipPath id="{clip}"><rect x="{LEFT}" y="{TOP}" width="{plot_w:.1f}" height="{plot_h:.1f}"/></clipPath>',
    ]
    parts += _axes(x0, x1, y0, y1, log_y, px, plot_w, plot_h, x_label, y_label)
    for index, (s, (x, y)) in enumerate(zip(series, points)):
        colour = s.colour or PALETTE[index % len(PALETTE)]
        sx, sy = px(x, y)
        finite = np.isfinite(sx) & np.isfinite(sy)
        dash = ' stroke-dasharray="6 4"' if s.dashed else ""
        if s.line:
            parts.append(
                f'<path class="series" d="{_path(sx, sy, finite)}" fill="none" stroke="{colour}" stroke-width="1.8"'
                f'{dash} clip-path="url(#{clip})"><title>{escape(s.label)}</title></path>'
            )
        if s.markers:
            raw_y = np.asarray(s.y, dtype=float)
            parts.append(f'<g class="markers" fill="{colour}" clip-path="url(#{clip})">')
            for i in np.flatnonzero(finite):
                parts.append(
                    f'<circle cx="{sx[i]:.1f}" cy="{sy[i]:.1f}" r="3.5"><title>{escape(s.label)}: '
                    f"({float(np.asarray(s.x, dtype=float)[i]):.4g}, {raw_y[i]:.4g})</title></circle>"
                )
            parts.append("</g>")
        row = legend_y + LEGEND_ROW * index
        key = (
            f'<line x1="{LEFT}" x2="{LEFT + 22}" y1="{row - 4:.1f}" y2="{row - 4:.1f}" stroke="{colour}" stroke-width="2"{dash}/>'
            if s.line
            else f'<circle cx="{LEFT + 11}" cy="{row - 4:.1f}" r="3.5" fill="{colour}"/>'
        )
        parts.append(f'{key}<text class="legend" x="{LEFT + 30}" y="{row:.1f}">{escape(s.label)}</text>')
    parts.append("</svg>")
    return "\n".join(parts) + "\n"


def _padded(low: float, high: float) -> tuple[float, float]:
    """[low, high] widened by 5 % on each side (by 1 around a single value)."""
    if high == low:
        return low - 1.0, high + 1.0
    pad = 0.05 * (high - low)
    return low - pad, high + pad


def _path(x: np.ndarray, y: np.ndarray, finite: np.ndarray) -> str:
    """The path data of a polyline through the finite points, a new sub-path after each gap."""
    commands, pen_down = [], False
    for i in range(len(x)):
        if not finite[i]:
            pen_down = False
            continue
        commands.append(f"{'L' if pen_down else 'M'}{x[i]:.1f} {y[i]:.1f}")
        pen_down = True
    return " ".join(commands)


def _axes(  # type: ignore[no-untyped-def]
    x0: float,
    x1: float,
    y0: float,
    y1: float,
    log_y: bool,
    px,
    plot_w: float,
    plot_h: float,
    x_label: str,
    y_label: str,
) -> list[str]:
    """Grid lines, tick labels, the frame and the axis labels."""
    parts = []
    for value in nice_ticks(x0, x1):
        x, _ = px(np.array(value), np.array(y0))
        parts.append(
            f'<line x1="{x:.1f}" x2="{x:.1f}" y1="{TOP}" y2="{TOP + plot_h:.1f}" stroke="#e3e3e3"/>'
            f'<text class="x-tick" x="{x:.1f}" y="{TOP + plot_h + 15:.1f}" text-anchor="middle">{value:g}</text>'
        )
    y_ticks = range(math.ceil(y0 - 1e-9), math.floor(y1 + 1e-9) + 1) if log_y else nice_ticks(y0, y1)
    for value in y_ticks:
        _, y = px(np.array(x0), np.array(float(value)))
        label = f"{10.0**value:g}" if log_y else f"{value:g}"
        parts.append(
            f'<line x1="{LEFT}" x2="{LEFT + plot_w:.1f}" y1="{y:.1f}" y2="{y:.1f}" stroke="#e3e3e3"/>'
            f'<text class="y-tick" x="{LEFT - 6}" y="{y + 4:.1f}" text-anchor="end">{label}</text>'
        )
    scale_note = " (log scale)" if log_y else ""
    parts += [
        f'<rect x="{LEFT}" y="{TOP}" width="{plot_w:.1f}" height="{plot_h:.1f}" fill="none" stroke="black"/>',
        f'<text x="{LEFT + plot_w / 2:.1f}" y="{TOP + plot_h + 34:.1f}" text-anchor="middle">{escape(x_label)}</text>',
        f'<text transform="translate(16 {TOP + plot_h / 2:.1f}) rotate(-90)" text-anchor="middle">'
        f"{escape(y_label)}{scale_note}</text>",
    ]
    return parts
