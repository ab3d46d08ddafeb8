"""Learning curves from curve.jsonl: one series per run, one marker per update, values on the axis."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import pytest

from toolimit.viz.svg_learning import learning_curve_svg

SVG = "{http://www.w3.org/2000/svg}"


def write_curve(path, rates):
    lines = [
        {
            "env_steps": 100 * (k + 1),
            "success_rate": rate,
            "goal_reward_mean": 10 * rate,
            "return_mean": rate,
            "action_std_mean": 0.1,
            "approx_kl": 0.01,
        }
        for k, rate in enumerate(rates)
    ]
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return path


def test_one_series_per_run_one_marker_per_update(tmp_path):
    curves = {
        "authors": write_curve(tmp_path / "a.jsonl", [0.0, 0.5, 1.0]),
        "toolimit": write_curve(tmp_path / "b.jsonl", [0.25]),
    }
    root = ET.fromstring(learning_curve_svg(curves, "success_rate"))
    groups = [g for g in root.iter(f"{SVG}g") if g.get("class") == "markers"]
    assert [len(list(g.iter(f"{SVG}circle"))) for g in groups] == [3, 1]
    titles = [c.find(f"{SVG}title").text for c in groups[0].iter(f"{SVG}circle")]
    assert titles == ["authors: (100, 0)", "authors: (200, 0.5)", "authors: (300, 1)"]
    assert [t.text for t in root.iter(f"{SVG}text") if t.get("class") == "legend"] == ["authors", "toolimit"]
    ticks = [t.text for t in root.iter(f"{SVG}text") if t.get("class") == "y-tick"]
    assert ticks[0] == "0" and ticks[-1] == "1"  # the success rate spans [0, 1] whatever the data


def test_goal_reward_axis_follows_the_data(tmp_path):
    root = ET.fromstring(learning_curve_svg({"run": write_curve(tmp_path / "a.jsonl", [0.0, 2.0])}, "goal_reward_mean"))
    ticks = [float(t.text) for t in root.iter(f"{SVG}text") if t.get("class") == "y-tick"]
    assert ticks[0] == 0.0 and ticks[-1] == 20.0
    root = ET.fromstring(learning_curve_svg({"run": write_curve(tmp_path / "b.jsonl", [1.5, 2.0])}, "goal_reward_mean"))
    assert [t.text for t in root.iter(f"{SVG}text") if t.get("class") == "y-tick"][0] == "0"  # from 0, not from 15


def test_unknown_metric_and_empty_curve_are_refused(tmp_path):
    with pytest.raises(ValueError, match="unknown metric"):
        learning_curve_svg({"run": write_curve(tmp_path / "a.jsonl", [0.0])}, "reward")
    (tmp_path / "empty.jsonl").write_text("")
    with pytest.raises(ValueError, match="no update recorded"):
        learning_curve_svg({"run": tmp_path / "empty.jsonl"})
