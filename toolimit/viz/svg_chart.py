"""A grouped bar chart on a log scale as a standalone SVG file, written without matplotlib.

The paper's results figure: for each group (a tool and demonstration) one bar per method, the goal
reward on a logarithmic axis, its interval as a whisker, and a horizontal line at the success
threshold. SVG is text: a browser opens it, a diff reads it, and no plotting library is needed.
Values <= 0 (nothing delivered) are drawn as a short stub at the axis' floor and labelled "0", since
a log axis has no zero; an interval's ends below the floor are drawn at the floor.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from xml.sax.saxutils import escape

#: Colours of successive methods (colour-blind friendly, Okabe-Ito).
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442", "#000000")


@dataclass(frozen=True)
class BarGroup:
    """One group of bars: a label, one value per series (None: not measured, no bar) and, if given,
    one interval (low, high) per series (None: no whisker)."""

    label: str
    values: Sequence[float | None]
    intervals: Sequence[tuple[float, float] | None] = ()


def log_bar_chart_svg(
    groups: Sequence[BarGroup],
    series: Sequence[str],
    title: str,
    y_label: str,
    threshold: float | None = None,
    threshold_label: str = "success",
    floor: float = 0.1,
) -> str:
    """The SVG text of a grouped bar chart with a log10 y axis from ``floor`` to the next power of
    ten above the largest value (or the threshold); ``series`` names the bars of every group."""
    if not groups or not series:
        raise ValueError("a chart needs at least one group and one series")
    for group in groups:
        if len(group.values) != len(series) or len(group.intervals) not in (0, len(series)):
            raise ValueError(
                f"group {group.label!r} has {len(group.values)} values and {len(group.intervals)} intervals "
                f"for {len(series)} series"
            )
    if floor <= 0:
        raise ValueError(f"floor must be > 0 on a log axis, got {floor}")
    measured = [v for group in groups for v in group.values if v is not None and v > 0]
    measured += [span[1] for group in groups for span in group.intervals if span is not None and span[1] > 0]
    top = max(measured + [threshold or floor, floor * 10])
    decades = (math.floor(math.log10(floor)), math.ceil(math.log10(top)))
    left, right, upper, lower = 70.0, 110.0, 40.0, 110.0  # the right margin holds the last tilted label
    bar, gap = 14.0, 18.0
    group_width = max(len(series) * bar + gap, 280.0 / len(groups))
    plot_width = len(groups) * group_width
    width, height = left + plot_width + right, upper + 260.0 + lower
    plot_height = 260.0

    def y_of(value: float) -> float:
        fraction = (math.log10(max(value, floor)) - decades[0]) / (decades[1] - decades[0])
        return upper + plot_height * (1.0 - fraction)

    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0f}" height="{height + 20 * len(series):.0f}" '
        'font-family="sans-serif" font-size="11">',
        f'<text x="{width / 2:.1f}" y="20" text-anchor="middle" font-size="14">{escape(title)}</text>',
        f'<text transform="translate(16 {upper + plot_height / 2:.1f}) rotate(-90)" text-anchor="middle">'
        f"{escape(y_label)} (log scale)</text>",
    ]
    for exponent in range(decades[0], decades[1] + 1):
        y = y_of(10.0**exponent)
        parts.append(f'<line x1="{left}" x2="{left + plot_width}" y1="{y:.1f}" y2="{y:.1f}" stroke="#ddd"/>')
        parts.append(f'<text x="{left - 6}" y="{y + 4:.1f}" text-anchor="end">{10.0**exponent:g}</text>')
    for g, group in enumerate(groups):
        x0 = left + (group_width - len(series) * bar) / 2 + g * group_width
        for s, value in enumerate(group.values):
            if value is None:
                continue
            x, y = x0 + s * bar, y_of(value) if value > 0 else upper + plot_height - 2.0
            parts.append(
                f'<rect x="{x:.1f}" y="{y:.1f}" width="{bar - 2}" height="{upper + plot_height - y:.1f}" '
                f'fill="{PALETTE[s % len(PALETTE)]}"><title>{escape(group.label)}, {escape(series[s])}: '
                f"{value:g}</title></rect>"
            )
            span = group.intervals[s] if group.intervals else None
            if span is not None:
                parts.append(_whisker(x + bar / 2 - 1, y_of(span[0]), y_of(span[1]), f"{span[0]:g} to {span[1]:g}"))
            if value <= 0:
                parts.append(f'<text x="{x + bar / 2 - 1:.1f}" y="{y - 3:.1f}" text-anchor="middle">0</text>')
        centre = x0 + len(series) * bar / 2
        parts.append(
            f'<text transform="translate({centre:.1f} {upper + plot_height + 12:.1f}) rotate(35)">'
            f"{escape(group.label)}</text>"
        )
    parts.append(
        f'<line x1="{left}" x2="{left}" y1="{upper}" y2="{upper + plot_height}" stroke="black"/>'
        f'<line x1="{left}" x2="{left + plot_width}" y1="{upper + plot_height}" y2="{upper + plot_height}" '
        'stroke="black"/>'
    )
    if threshold is not None and threshold > 0:
        y = y_of(threshold)
        parts.append(
            f'<line x1="{left}" x2="{left + plot_width}" y1="{y:.1f}" y2="{y:.1f}" stroke="red" '
            f'stroke-dasharray="6 4"/><text x="{left + plot_width}" y="{y - 4:.1f}" text-anchor="end" '
            f'fill="red">{escape(threshold_label)} ({threshold:g})</text>'
        )
    for s, name in enumerate(series):
        y = height + 20 * s - 10
        parts.append(
            f'<rect x="{left}" y="{y - 9:.1f}" width="10" height="10" fill="{PALETTE[s % len(PALETTE)]}"/>'
            f'<text x="{left + 16}" y="{y:.1f}">{escape(name)}</text>'
        )
    parts.append("</svg>")
    return "\n".join(parts) + "\n"


def _whisker(x: float, y_low: float, y_high: float, label: str) -> str:
    """A vertical line from ``y_low`` to ``y_high`` at ``x`` with caps (SVG coordinates)."""
    caps = "".join(
        f'<line x1="{x - 3:.1f}" x2="{x + 3:.1f}" y1="{y:.1f}" y2="{y:.1f}" stroke="#333"/>' for y in (y_low, y_high)
    )
    return (
        f'<g><title>95 % interval: {escape(label)}</title><line x1="{x:.1f}" x2="{x:.1f}" y1="{y_low:.1f}" '
        f'y2="{y_high:.1f}" stroke="#333"/>{caps}</g>'
    )
