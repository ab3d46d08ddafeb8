"""The results pages' charts, drawn at build time from the JSON committed under benchmarks/results/.

Each results page holds a ``{results-chart} NAME`` directive: the chart NAME is drawn from its JSON
with ``toolimit.viz`` (SVG, no plotting library), followed by the data's path, the command that
made it and the commit it records. A chart whose JSON is missing or lacks a field fails the build
(a results page that no longer matches its data is an error, not a warning). The paper's figure is
drawn by ``toolimit.experiments.report.write_results`` itself from ``results.json`` (every seed's
cells, or the one seed's of the figure measured before there were seeds; the figure within the
limits and the one with the authors' span) and compared with the committed SVG, so the committed
chart cannot drift from its table.
"""

from __future__ import annotations

import functools
import json
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.application import Sphinx
from sphinx.errors import ExtensionError

REPO = Path(__file__).resolve().parents[2]
RESULTS = REPO / "benchmarks" / "results"
#: Where the charts are written, inside the source folder so that Sphinx copies them as images.
GENERATED = REPO / "docs" / "results" / "_generated"


@dataclass(frozen=True)
class Chart:
    """One chart: its SVG, the data it was drawn from, the command that made the data, its commit."""

    svg: str
    source: str
    command: str
    commit: str


def _load(relative: str) -> dict[str, Any]:
    return json.loads((RESULTS / relative).read_text())


def _commit(record: dict[str, Any]) -> str:
    note = record.get("commit_note")
    return f"{record['commit']} ({note})" if note else str(record["commit"])


def _success_bars(labels: list[str], values: list[list[float | None]], series: list[str], title: str) -> str:
    """Success rates as grouped bars; a log axis from 0.01 (``log_bar_chart_svg``), 0 as a stub."""
    from toolimit.viz.svg_chart import BarGroup, log_bar_chart_svg

    groups = [BarGroup(label, row) for label, row in zip(labels, values)]
    return log_bar_chart_svg(groups, series, title=title, y_label="success rate", threshold=0.8, floor=0.01)


@functools.cache
def _figure_charts(folder: str) -> tuple[dict[str, Any], dict[str, str]]:
    """The record of ``FOLDER/results.json`` and each tool's chart drawn from it, once per build:
    the summaries behind them bootstrap every cell."""
    from toolimit.experiments.report import read_results, write_results

    record = _load(f"{folder}/results.json")
    preset, runs = read_results(record)
    with tempfile.TemporaryDirectory() as scratch:
        written = write_results(Path(scratch), runs, preset)
        charts = {path.stem.removeprefix("results_"): path.read_text() for path in written if path.suffix == ".svg"}
    return record, charts


def paper_figure(folder: str, tool: str) -> Chart:
    """The figure of ``FOLDER/results.json``, of either layout: one seed's cells (the figure
    measured before there were seeds) or every seed's."""
    record, charts = _figure_charts(folder)
    svg = charts[tool]
    committed = (RESULTS / folder / f"results_{tool}.svg").read_text()
    if svg != committed:
        raise ExtensionError(f"benchmarks/results/{folder}/results_{tool}.svg is not the chart of results.json")
    return Chart(svg, f"benchmarks/results/{folder}/results.json", record["command"], _commit(record))


def learning_grid() -> Chart:
    record = _load("steady_learning.json")
    runs = list(record["runs"].values())
    labels = [f"{run['demo']}, seed {run['seed']}" for run in runs]
    values = [[run["success_rate"], run["stochastic_success_rate"]] for run in runs]
    svg = _success_bars(labels, values, ["deterministic", "stochastic"], "Panda spade: success over 20 episodes")
    commits = sorted({run.get("commit", "?") for run in runs})
    return Chart(
        svg,
        "benchmarks/results/steady_learning.json",
        "python benchmarks/steady_learning.py",
        "per run: " + ", ".join(commits),
    )


def adr() -> Chart:
    labels, values, commits = [], [], []
    for seed in (0, 1, 2):
        evaluation = _load(f"adr_spade3d_box_offset_seed{seed}/evaluation.json")
        reachable = evaluation["heat_map"]["standing_reachable_in_rectangle"]
        succeeding = evaluation["heat_map"]["succeeding_reachable_in_rectangle"]
        labels.append(f"seed {seed} ({succeeding} of {reachable})")
        values.append([succeeding / reachable, evaluation["success_rate"]])
        commits.append(evaluation["commit"])
    control = _load("adr_spade3d_uniform_rectangle_seed0/evaluation.json")
    heat = control["heat_map"]
    labels.append(
        f"no curriculum, seed 0 ({heat['succeeding_reachable_in_rectangle']} of {heat['standing_reachable_in_rectangle']})"
    )
    values.append(
        [heat["succeeding_reachable_in_rectangle"] / heat["standing_reachable_in_rectangle"], control["success_rate"]]
    )
    commits.append(control["commit"])
    svg = _success_bars(
        labels,
        values,
        ["reachable positions succeeding", "aligned box"],
        "Domain randomisation, Panda spade, 12 M steps",
    )
    command = (
        "toolimit learn --env toolimit/Spade3D-v0 --adr --preset toolimit --learning-rate 1e-4 --target-kl 0.1 "
        "--timesteps 12000000 --adr-every 8 --seed S --out runs/adr_offset; "
        "toolimit evaluate --policy runs/adr_offset --heat-map runs/adr_offset/heat_map.svg"
    )
    return Chart(
        svg,
        "benchmarks/results/adr_spade3d_box_offset_seed{0,1,2}/evaluation.json",
        command,
        ", ".join(dict.fromkeys(commits)),
    )


def scythe() -> Chart:
    labels, values, commits = [], [], []
    for demo in range(5):
        evaluation = _load(f"scythe_action_limit/scythe_0{demo}/evaluation.json")
        labels.append(f"scythe_0{demo}")
        values.append([evaluation["success_rate"]])
        commits.append(evaluation["commit"])
    svg = _success_bars(
        labels, values, ["final policy"], "Scythe with the authors' action span: success over 20 episodes"
    )
    command = (
        "toolimit run --tool scythe --robot panda --demo data/demos/scythe_0i.npz --action-limit 3 --out runs/scythe_0i"
    )
    return Chart(
        svg,
        "benchmarks/results/scythe_action_limit/scythe_0*/evaluation.json",
        command,
        ", ".join(dict.fromkeys(commits)),
    )


def timed_tools() -> Chart:
    record = _load("timed_tools_replay.json")
    rows = record["after"]
    labels = [Path(row["demo"]).stem for row in rows]
    values = [[row.get("tool_alone_success"), row.get("robot_success")] for row in rows]
    svg = _success_bars(labels, values, ["tool alone", "robot"], "Timed tools: replay success of the aligned episode")
    return Chart(svg, "benchmarks/results/timed_tools_replay.json", str(record["command"]), _commit(record))


def talos() -> Chart:
    from toolimit.viz.svg_chart import BarGroup, log_bar_chart_svg

    record = _load("talos_selection.json")
    rows = [row for row in record["rows"] if "variant" in row]
    groups = [BarGroup(row["variant"], [row["best_spheres"], row["median_spheres"]]) for row in rows]
    svg = log_bar_chart_svg(
        groups,
        ["best robot replay", "median"],
        title="Talos: robot replays of 40 candidates (spheres in the box)",
        y_label="spheres",
        threshold=10.0,
    )
    return Chart(svg, "benchmarks/results/talos_selection.json", str(record["command"]), _commit(record))


def video_lift() -> Chart:
    from toolimit.viz.svg_chart import BarGroup, log_bar_chart_svg

    record = _load("video_lift/results.json")
    rows = [row for row in record["lift"] if row["noise_px"] == 3.0]
    groups = [BarGroup(row["name"], [row["head_error_cm"], row["axis_error_deg"]]) for row in rows]
    svg = log_bar_chart_svg(
        groups,
        ["head error (cm)", "axis error (deg)"],
        title="Video lift at 3 px of noise, mean over 5 seeds",
        y_label="error",
        floor=0.1,
    )
    return Chart(svg, "benchmarks/results/video_lift/results.json", "python benchmarks/video_lift.py", _commit(record))


def performance() -> Chart:
    from toolimit.viz.svg_chart import BarGroup, log_bar_chart_svg

    groups, commits = [], []
    for name in ("SpadePlanar", "Hammer3D", "Spade3D"):
        record = _load(f"learning_throughput_{name}.json")
        groups.append(BarGroup(name, [record["ratio"]]))
        commits.append(record["commit"])
    svg = log_bar_chart_svg(
        groups,
        ["training throughput / SB3's ceiling"],
        title="Learning throughput against SB3's ceiling",
        y_label="ratio",
        threshold=0.7,
        threshold_label="target",
        floor=0.01,
    )
    return Chart(
        svg,
        "benchmarks/results/learning_throughput_*.json",
        "python benchmarks/learning_throughput.py --env toolimit/NAME-v0",
        ", ".join(dict.fromkeys(commits)),
    )


CHARTS: dict[str, Callable[[], Chart]] = {
    "paper_figure_spade": lambda: paper_figure("figure_within_limits", "spade"),
    "paper_figure_hammer": lambda: paper_figure("figure_within_limits", "hammer"),
    "paper_figure_scythe": lambda: paper_figure("figure_within_limits", "scythe"),
    "paper_figure_span_spade": lambda: paper_figure("reproduce", "spade"),
    "paper_figure_span_hammer": lambda: paper_figure("reproduce", "hammer"),
    "paper_figure_span_scythe": lambda: paper_figure("reproduce", "scythe"),
    "learning_grid": learning_grid,
    "adr": adr,
    "scythe": scythe,
    "timed_tools": timed_tools,
    "talos": talos,
    "video_lift": video_lift,
    "performance": performance,
}


class ResultsChart(Directive):
    """``{results-chart} NAME``: the chart, then where its data comes from."""

    required_arguments = 1

    def run(self) -> list[nodes.Node]:
        name = self.arguments[0]
        if name not in CHARTS:
            raise self.error(f"unknown results chart {name!r}; known: {', '.join(CHARTS)}")
        try:
            chart = CHARTS[name]()
        except (KeyError, FileNotFoundError, TypeError) as error:
            raise self.error(f"results chart {name!r}: its data does not match ({error!r})") from error
        GENERATED.mkdir(parents=True, exist_ok=True)
        path = GENERATED / f"{name}.svg"
        if not path.exists() or path.read_text() != chart.svg:
            path.write_text(chart.svg)
        env = self.state.document.settings.env
        env.note_dependency(str(path))
        image = nodes.image(uri=f"/results/_generated/{name}.svg", alt=f"chart: {name}", classes=["results-chart"])
        image["candidates"] = {"*": f"results/_generated/{name}.svg"}
        source = nodes.paragraph()
        source += nodes.Text("Data: ")
        source += nodes.literal(text=chart.source)
        source += nodes.Text("; made by ")
        source += nodes.literal(text=chart.command)
        source += nodes.Text(f"; commit {chart.commit}.")
        return [image, source]


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("results-chart", ResultsChart)
    return {"version": "1", "parallel_read_safe": True}
