"""scripts/restore_figure_cells.py: a committed figure's cells go back where a reproduction resumes
from them."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np

from toolimit.experiments.cells import CellResult, Experiment

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "restore_figure_cells.py"


def _script():
    spec = importlib.util.spec_from_file_location("restore_figure_cells", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_each_seeds_cells_are_written_as_the_reproduction_saves_them(tmp_path):
    experiment = Experiment("spade", "3d", "panda", Path("data/demos/spade_00.npz"))
    cells = {
        seed: CellResult.of(experiment, "final", np.array([20.0, 10.0 + seed]), np.array([True, seed == 1]))
        for seed in (0, 1)
    }
    results = tmp_path / "results.json"
    record = {
        "preset": {"name": "full", "quick": False, "settings_changes": {}},
        "seeds": [0, 1],
        "cells": [cell.record() | {"seed": seed} for seed, cell in cells.items()],
    }
    results.write_text(json.dumps(record))
    assert _script().restore(results, tmp_path / "figure") == 2
    for seed, cell in cells.items():
        folder = tmp_path / "figure" / f"seed_{seed}"
        assert CellResult.load(folder / "cells" / "spade-3d-panda-spade_00-final.json") == cell
        assert json.loads((folder / "results.json").read_text())["preset"]["seed"] == seed
