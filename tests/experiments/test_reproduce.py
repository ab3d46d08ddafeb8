"""``toolimit reproduce --preset quick``: every method's cell measured, saved, reported, and resumed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from toolimit.cli import main as toolimit
from toolimit.experiments.cells import METHODS, CellResult
from toolimit.experiments.report import markdown_table

REPO = Path(__file__).resolve().parents[2]
EXPERIMENT = "spade-planar-planar3-spade_03"


@pytest.fixture(scope="module")
def quick_results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("reproduce")
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(REPO)  # the preset names the shipped demonstrations relative to the checkout
        assert toolimit(["reproduce", "--preset", "quick", "--out", str(out), "--quiet"]) == 0
    return out


def test_every_method_has_a_cell_with_the_figures_fields(quick_results: Path) -> None:
    cells = json.loads((quick_results / "results.json").read_text())["cells"]
    assert sorted(cell["method"] for cell in cells) == sorted(METHODS)
    for cell in cells:
        assert {"tool", "demo", "robot", "method", "goal_reward", "success_rate"} <= cell.keys()
        assert (cell["tool"], cell["robot"], cell["demo"]) == ("spade", "planar3", "spade_03")
        assert 0.0 <= cell["success_rate"] <= 1.0 and len(cell["goal_rewards"]) == 4
    by_method = {cell["method"]: cell for cell in cells}
    # The aligned motion and the robot's trajectory deliver sand; PPO from scratch on 2,000 steps does not.
    assert by_method["tool_only"]["goal_reward"] >= 10 and by_method["trajopt"]["goal_reward"] >= 10
    assert by_method["sparse_ppo"]["goal_reward"] == 0.0
    assert by_method["final"]["env_steps"] > by_method["sparse_ppo"]["env_steps"] > 0  # cloning rollouts on top


def test_the_table_and_the_figure_are_written(quick_results: Path) -> None:
    table = (quick_results / "results.md").read_text()
    assert "| spade | planar | planar3 | spade_03 |" in table
    svg = (quick_results / "results_spade.svg").read_text()
    assert svg.startswith("<svg") and "success (10)" in svg


def test_a_second_run_skips_saved_cells_and_a_removed_cell_comes_back_the_same(
    quick_results: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    removed = quick_results / "cells" / f"{EXPERIMENT}-trajopt.json"
    before = CellResult.load(removed)
    removed.unlink()
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(REPO)
        assert toolimit(["reproduce", "--preset", "quick", "--out", str(quick_results), "--quiet"]) == 0
    output = capsys.readouterr().out
    assert "[learning] done earlier" in output and "sparse_ppo:" not in output  # only the missing cell ran
    assert CellResult.load(removed) == before  # same seed, same rollouts


def test_markdown_marks_unmeasured_methods() -> None:
    cell = CellResult("hammer", "3d", "panda", "hammer_00", "final", 1.0, 1.0, [1.0], 10, 1.0)
    assert markdown_table([cell]).splitlines()[-1] == "| hammer | 3d | panda | hammer_00 | - | - | 1.0 (1.00) | - | - |"


def test_a_demonstration_of_an_unknown_tool_is_a_one_line_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    demo = tmp_path / "shovel_00.npz"
    demo.write_bytes(b"")
    assert toolimit(["reproduce", "--demo", str(demo), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and "must start with one of spade, hammer, scythe" in error
    assert not (tmp_path / "out").exists()
