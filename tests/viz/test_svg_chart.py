"""The log-scale bar chart: valid SVG, one bar per measured value, zeros labelled, the threshold drawn."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import pytest

from toolimit.viz.svg_chart import PALETTE, BarGroup, log_bar_chart_svg

SVG = "{http://www.w3.org/2000/svg}"
SERIES = ["tool_only", "final", "sparse_ppo"]


def chart(groups, threshold=10.0):
    return ET.fromstring(log_bar_chart_svg(groups, SERIES, "spade", "goal reward", threshold=threshold))


def bars(root):
    """(fill, y, height, title) of every data bar (legend squares have no title)."""
    return [
        (r.get("fill"), float(r.get("y")), float(r.get("height")), r.find(f"{SVG}title").text)
        for r in root.iter(f"{SVG}rect")
        if r.find(f"{SVG}title") is not None
    ]


def test_one_bar_per_measured_value_in_its_series_colour():
    root = chart([BarGroup("spade_00", [8.0, 20.0, 0.0]), BarGroup("spade_01", [3.0, None, 0.0])])
    drawn = bars(root)
    assert len(drawn) == 5  # the None is not drawn
    assert [fill for fill, *_ in drawn] == [PALETTE[0], PALETTE[1], PALETTE[2], PALETTE[0], PALETTE[2]]
    assert drawn[1][3] == "spade_00, final: 20"


def test_heights_are_logarithmic_and_zero_is_a_labelled_stub():
    root = chart([BarGroup("a", [1.0, 10.0, 0.0])])
    (_, _, one, _), (_, _, ten, _), (_, _, zero, _) = bars(root)
    axis_floor = 0.1  # the default floor: 1 is one decade above it, 10 two
    assert ten == pytest.approx(2 * one, rel=1e-2)
    assert one / math.log10(1.0 / axis_floor) > 0 and zero < 3
    assert any(t.text == "0" for t in root.iter(f"{SVG}text"))


def test_the_threshold_line_is_drawn_and_labelled():
    root = chart([BarGroup("a", [1.0, 10.0, 0.0])], threshold=10.0)
    dashed = [line for line in root.iter(f"{SVG}line") if line.get("stroke") == "red"]
    assert len(dashed) == 1
    assert any(t.text == "success (10)" for t in root.iter(f"{SVG}text"))
    assert not [line for line in chart([BarGroup("a", [1, 2, 3])], None).iter(f"{SVG}line") if line.get("stroke") == "red"]


def test_an_interval_is_a_whisker_on_its_bar_from_low_to_high():
    root = chart([BarGroup("a", [1.0, 10.0, 0.0], [(0.5, 2.0), None, (0.0, 0.4)])])
    whiskers = [g for g in root.iter(f"{SVG}g") if g.find(f"{SVG}title").text.startswith("95 % interval")]
    assert [g.find(f"{SVG}title").text for g in whiskers] == ["95 % interval: 0.5 to 2", "95 % interval: 0 to 0.4"]
    (_, one_top, _, _), *_ = bars(root)
    stem = whiskers[0].find(f"{SVG}line")
    low, high = float(stem.get("y1")), float(stem.get("y2"))
    assert high < one_top < low  # around the bar's top: 2 above it, 0.5 below
    assert float(whiskers[1].find(f"{SVG}line").get("y1")) == pytest.approx(300.0)  # 0 drawn at the axis' floor


@pytest.mark.parametrize(
    ("groups", "message"),
    [
        ([], "at least one group"),
        ([BarGroup("a", [1.0])], "group 'a' has 1 values and 0 intervals for 3 series"),
        ([BarGroup("a", [1.0, 2.0, 3.0], [(0.5, 1.5)])], "group 'a' has 3 values and 1 intervals for 3 series"),
    ],
)
def test_bad_input_is_refused(groups, message):
    with pytest.raises(ValueError, match=message):
        log_bar_chart_svg(groups, SERIES, "t", "y")
