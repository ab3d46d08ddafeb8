"""``toolimit reproduce --seed 0,1,2``: a folder per seed, and the figure over every seed's cells.

The experiments' work is replaced by a stand-in that saves made-up cells (the quick preset's real
run is tests/experiments/test_reproduce.py's): what is checked here is the layout, the refusals and
the aggregation.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from toolimit.artifacts import save_json
from toolimit.cli import main as toolimit
from toolimit.experiments.cells import CellResult, Experiment
from toolimit.experiments.methods import missing_methods
from toolimit.experiments.report import read_results, write_results
from toolimit.experiments.summary import summarise_cells, summarise_methods

REPO = Path(__file__).resolve().parents[2]
EXPERIMENT = "spade-planar-planar3-spade_03"
#: Each method's success probability in the made-up cells.
SUCCESS = {"tool_only": 0.3, "trajopt": 0.6, "final": 0.95, "sparse_ppo": 0.0, "dense_ppo": 0.5, "lfd": 0.9}


def made_up_cell(experiment: Experiment, method: str, seed: int, episodes: int = 20) -> CellResult:
    """A cell drawn from ``method``'s success probability, its own generator per seed."""
    rng = np.random.default_rng([seed, len(method)])
    successes = rng.random(episodes) < SUCCESS[method]
    return CellResult.of(experiment, method, np.where(successes, 12.0, 3.0) + rng.random(episodes), successes)


@pytest.fixture
def stand_in(monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, str]]:
    """``reproduce_experiment`` replaced by one saving made-up cells; the (seed, experiment) it ran."""
    ran: list[tuple[int, str]] = []

    def reproduce_experiment(experiment, chosen, out, seed, methods, progress, say):
        ran.append((seed, experiment.name))
        for method in missing_methods(experiment, out, methods):
            save_json(
                out / "cells" / f"{experiment.cell_key(method)}.json", made_up_cell(experiment, method, seed).record()
            )
            say(experiment.name, f"{method}: saved")
        return 0

    monkeypatch.setattr("toolimit.experiments.reproduce.reproduce_experiment", reproduce_experiment)
    monkeypatch.chdir(REPO)
    return ran


def test_each_seed_is_a_reproduction_of_its_own_and_the_figure_puts_them_side_by_side(
    stand_in: list[tuple[int, str]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "figure"
    assert toolimit(["reproduce", "--preset", "quick", "--seed", "0,1", "--out", str(out), "--quiet"]) == 0
    assert stand_in == [(0, EXPERIMENT), (1, EXPERIMENT)]
    said = capsys.readouterr().out
    assert f"[seed_1/{EXPERIMENT}] final: saved" in said, said
    for seed in (0, 1):
        record = json.loads((out / f"seed_{seed}" / "results.json").read_text())
        assert record["preset"]["seed"] == seed and record["seeds"] == [seed] and len(record["cells"]) == 6
    record = json.loads((out / "results.json").read_text())
    assert "seed" not in record["preset"] and record["seeds"] == [0, 1] and len(record["cells"]) == 12
    assert {summary["method"]: summary["seeds"] for summary in record["summary"]} == dict.fromkeys(SUCCESS, [0, 1])
    final = next(s for s in record["summary"] if s["method"] == "final")["success"]
    assert final["low"] <= final["value"] <= final["high"]
    assert (out / "results_spade.svg").read_text().count("95 % interval") == 6
    # a later sitting adds seed 2 alone; the figure then has the three
    assert toolimit(["reproduce", "--preset", "quick", "--seed", "2", "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "results.json").read_text())["seeds"] == [0, 1, 2]
    assert "over seeds 0, 1, 2" in (out / "results.md").read_text()
    # and a resumed call runs nothing that is saved
    assert toolimit(["reproduce", "--preset", "quick", "--seed", "0,1,2", "--out", str(out), "--quiet"]) == 0
    assert len(stand_in) == 6 and len(json.loads((out / "results.json").read_text())["cells"]) == 18


def test_jobs_run_every_seeds_experiments_in_one_queue(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``--jobs 2`` with two seeds of one experiment: a child per seed, each its own ``--seed``."""
    from toolimit.experiments import reproduce

    commands: list[list[str]] = []

    class Child:
        def __init__(self, command, **kwargs):
            commands.append(command)
            self.returncode = 0

        def poll(self):
            return 0

    monkeypatch.setattr(reproduce.subprocess, "Popen", Child)
    monkeypatch.setattr(reproduce.time, "sleep", lambda seconds: None)
    monkeypatch.chdir(REPO)
    out = tmp_path / "figure"
    assert toolimit(["reproduce", "--preset", "quick", "--seed", "3,5", "--jobs", "2", "--out", str(out)]) == 0
    assert [command[command.index("--seed") + 1] for command in commands] == ["3", "5"]
    assert all(command[command.index("--out") + 1] == str(out) for command in commands)
    assert (out / "seed_5" / "logs" / f"{EXPERIMENT}.log").is_file()


def test_a_cell_missing_from_one_seed_says_how_many_seeds_it_has(tmp_path: Path) -> None:
    experiment = Experiment("spade", "planar", "planar3", Path("spade_03.npz"))
    runs = {seed: [made_up_cell(experiment, m, seed) for m in ("trajopt", "final", "lfd")] for seed in (0, 1, 2)}
    runs[2] = [cell for cell in runs[2] if cell.method != "lfd"]  # seed 2's LfD still learning
    write_results(tmp_path, runs, {"name": "quick", "quick": True, "settings_changes": {}})
    summaries = {s["method"]: s for s in json.loads((tmp_path / "results.json").read_text())["summary"]}
    assert summaries["lfd"]["seeds"] == [0, 1] and summaries["final"]["seeds"] == [0, 1, 2]
    row = (tmp_path / "results.md").read_text().split("| spade | planar | planar3 | spade_03 |")[1].splitlines()[0]
    lfd = row.split("|")[5]
    assert lfd.strip().endswith(", 2 of 3 seeds") and "of 3 seeds" not in row.split("|")[2]
    lfd_runs = next(a for a in summarise_methods(runs) if a.method == "lfd")
    assert lfd_runs.runs == 2 and lfd_runs.improvement_demos == ["spade_03"]


def test_an_export_replayed_on_fewer_seeds_says_on_how_many(tmp_path: Path) -> None:
    experiment = Experiment("spade", "3d", "panda", Path("spade_00.npz"))
    replayed = {"goal_reward": [15.0, 3.0], "successes": [True, False], "success_rate": 0.5, "episodes": 2}
    runs = {
        seed: [dataclasses.replace(made_up_cell(experiment, "final", seed), exported=replayed if seed < 2 else None)]
        for seed in (0, 1, 2)
    }
    write_results(tmp_path, runs, {"name": "full", "quick": False, "settings_changes": {}})
    (summary,) = json.loads((tmp_path / "results.json").read_text())["summary"]
    assert summary["exported_seeds"] == [0, 1] and summary["exported_success"]["value"] == 0.5
    row = (tmp_path / "results.md").read_text().split("| spade | 3d | panda | spade_00 |")[1].splitlines()[0]
    final, exported = row.split("|")[2], row.split("|")[-2]
    assert exported.strip().endswith(", 2 of 3 seeds") and "seeds" not in final


def test_the_seeds_of_a_cell_average_their_means() -> None:
    experiment = Experiment("hammer", "3d", "panda", Path("hammer_00.npz"))
    runs = {
        0: [CellResult.of(experiment, "final", np.ones(10), np.ones(10, bool))],
        1: [CellResult.of(experiment, "final", np.zeros(10), np.zeros(10, bool))],
    }
    (summary,) = summarise_cells(runs)
    assert summary.goal_reward.value == 0.5 and summary.success.value == 0.5 and summary.episodes == 10
    assert summary.success.low == 0.0 and summary.success.high == 1.0  # two seeds that disagree entirely


def test_a_results_json_of_the_single_seed_layout_reads_as_its_seeds(tmp_path: Path) -> None:
    """The committed figure (cells without seeds, its preset's seed) is seed 0's; what this module
    writes reads back as it was."""
    committed = json.loads((REPO / "benchmarks" / "results" / "reproduce" / "results.json").read_text())
    preset, runs = read_results(committed)
    assert list(runs) == [committed["preset"]["seed"]] and len(runs[0]) == len(committed["cells"])
    assert all(cell.successes is None for cell in runs[0])  # made before successes were recorded
    write_results(tmp_path, runs, preset)
    assert read_results(json.loads((tmp_path / "results.json").read_text())) == (preset, runs)


def test_old_cells_rebuild_their_episodes_successes_from_the_rate() -> None:
    cell = CellResult("spade", "3d", "panda", "spade_00", "final", 1.0, 0.75, [1.0] * 4, 0, 0.0)
    assert cell.episode_successes().tolist() == [True, True, True, False]
    broken = CellResult("spade", "3d", "panda", "spade_00", "final", 1.0, 0.7, [1.0] * 4, 0, 0.0)
    with pytest.raises(ValueError, match="not a count of 4 episodes"):
        broken.episode_successes()


@pytest.mark.parametrize(
    ("seeds", "said"),
    [
        ("0,0", "seed 0 given twice in '0,0'"),
        ("0,x", "expected non-negative integers separated by commas, e.g. 0,1,2, got '0,x'"),
        ("-1", "got '-1'"),
        ("", "got ''"),
    ],
)
def test_a_bad_seed_list_is_a_one_line_error(
    seeds: str, said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_info:
        toolimit(["reproduce", "--preset", "quick", f"--seed={seeds}", "--out", str(tmp_path / "out")])
    assert exit_info.value.code == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and said in error, error
    assert not (tmp_path / "out").exists()


def test_a_folder_of_the_single_seed_layout_is_refused_with_the_move_that_fixes_it(
    stand_in: list[tuple[int, str]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "figure"
    (out / "cells").mkdir(parents=True)
    save_json(out / "results.json", {"preset": {"name": "quick", "quick": True, "seed": 4}, "cells": []})
    assert toolimit(["reproduce", "--preset", "quick", "--out", str(out), "--quiet"]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and not stand_in
    assert f"mv {out} {out}.seed_4 && mkdir {out} && mv {out}.seed_4 {out}/seed_4" in error
    assert sorted(p.name for p in out.iterdir()) == ["cells", "results.json"], "nothing written"
