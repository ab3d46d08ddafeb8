"""The SVG line plot: valid XML, one path or marker group per series, values mapped onto the axes."""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from toolimit.viz.svg_chart import PALETTE
from toolimit.viz.svg_plot import LEFT, TOP, Series, line_plot_svg, nice_ticks, outline

SVG = "{http://www.w3.org/2000/svg}"


def path_points(path: ET.Element) -> list[list[tuple[float, float]]]:
    """The sub-paths of a path's ``d``, each a list of (x, y) px."""
    subpaths: list[list[tuple[float, float]]] = []
    for command, x, y in re.findall(r"([ML])([-\d.]+) ([-\d.]+)", path.get("d")):
        if command == "M":
            subpaths.append([])
        subpaths[-1].append((float(x), float(y)))
    return subpaths


def frame(root: ET.Element) -> tuple[float, float, float, float]:
    """x, y, width, height of the plotting area's frame (the rect without fill)."""
    rect = next(r for r in root.iter(f"{SVG}rect") if r.get("fill") == "none")
    return tuple(float(rect.get(key)) for key in ("x", "y", "width", "height"))  # type: ignore[return-value]


def test_values_are_mapped_linearly_onto_the_given_ranges():
    text = line_plot_svg(
        [Series("a", [0, 5, 10], [0, 50, 100])], "t", "x (s)", "y (m)", x_range=(0, 10), y_range=(0, 100)
    )
    root = ET.fromstring(text)
    left, top, width, height = frame(root)
    assert (left, top) == (LEFT, TOP)
    (points,) = path_points(root.find(f".//{SVG}path"))
    assert points[0] == pytest.approx((left, top + height), abs=0.06)  # (0, 0): bottom left
    assert points[1] == pytest.approx((left + width / 2, top + height / 2), abs=0.06)
    assert points[2] == pytest.approx((left + width, top), abs=0.06)  # (10, 100): top right
    texts = [t.text for t in root.iter(f"{SVG}text")]
    assert "x (s)" in texts and "y (m)" in texts and "t" in texts


def test_a_series_each_with_its_colour_markers_and_legend():
    series = [Series("speed", [0, 1, 2], [1, 2, 3]), Series("keypoints", [1], [2], line=False, markers=True)]
    root = ET.fromstring(line_plot_svg(series, "t", "x", "y"))
    paths = [p for p in root.iter(f"{SVG}path") if p.get("class") == "series"]
    assert len(paths) == 1 and paths[0].get("stroke") == PALETTE[0]
    groups = [g for g in root.iter(f"{SVG}g") if g.get("class") == "markers"]
    assert len(groups) == 1 and groups[0].get("fill") == PALETTE[1]
    (marker,) = groups[0].iter(f"{SVG}circle")
    assert marker.find(f"{SVG}title").text == "keypoints: (1, 2)"
    assert [t.text for t in root.iter(f"{SVG}text") if t.get("class") == "legend"] == ["speed", "keypoints"]


def test_a_non_finite_value_breaks_the_line():
    root = ET.fromstring(line_plot_svg([Series("s", [0, 1, 2, 3, 4], [0, 1, np.nan, 1, 0])], "t", "x", "y"))
    assert [len(sub) for sub in path_points(root.find(f".//{SVG}path"))] == [2, 2]


def test_log_axis_has_decade_ticks_and_drops_non_positive_values():
    root = ET.fromstring(
        line_plot_svg([Series("loss", [0, 1, 2, 3], [1.0, 0.1, 0.01, 0.0])], "t", "x", "y", log_y=True)
    )
    ticks = [t.text for t in root.iter(f"{SVG}text") if t.get("class") == "y-tick"]
    assert ticks == ["0.01", "0.1", "1"]
    (points,) = path_points(root.find(f".//{SVG}path"))
    assert len(points) == 3
    ys = [y for _, y in points]
    assert ys[1] - ys[0] == pytest.approx(ys[2] - ys[1], abs=0.11)  # equal steps per decade


def test_equal_aspect_gives_both_axes_one_scale():
    root = ET.fromstring(
        line_plot_svg([Series("s", [0, 2], [0, 1])], "t", "x", "y", equal_aspect=True, x_range=(0, 2), y_range=(0, 1))
    )
    _, _, width, height = frame(root)
    assert width / 2 == pytest.approx(height / 1, rel=1e-3)


def test_two_figures_have_distinct_clip_paths():
    ids = {
        ET.fromstring(line_plot_svg([Series("s", [0, 1], [0, top])], "t", "x", "y")).find(f".//{SVG}clipPath").get("id")
        for top in (1, 2)
    }
    assert len(ids) == 2


def test_nice_ticks_are_round_and_inside():
    assert nice_ticks(0, 1) == [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
    assert nice_ticks(-0.05, 1.05) == [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
    assert nice_ticks(3, 870) == [200, 400, 600, 800]


def test_outline_of_a_turned_rectangle():
    x, y = outline([1.0, 2.0, 0.5, 0.25, math.pi / 2])
    assert (x[0], y[0]) == pytest.approx((x[-1], y[-1]))  # closed
    np.testing.assert_allclose(sorted(set(np.round(x, 9))), [0.75, 1.25])  # its length now along y
    np.testing.assert_allclose(sorted(set(np.round(y, 9))), [1.5, 2.5])


@pytest.mark.parametrize(
    ("series", "message"),
    [
        ([], "at least one series"),
        ([Series("s", [0, 1], [0])], "1-D of one length"),
        ([Series("s", [np.nan], [0])], "no finite"),
    ],
)
def test_bad_input_is_refused(series, message):
    with pytest.raises(ValueError, match=message):
        line_plot_svg(series, "t", "x", "y")
