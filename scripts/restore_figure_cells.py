"""Put a committed figure's cells back into a reproduction's folder, so that it resumes without them.

A long ``toolimit reproduce`` is committed as it goes (``benchmarks/results/.../results.json``: its
cells and preset, with the commit and command that made them); the experiments' folders are not.
This writes each committed cell to ``OUT/seed_<S>/cells/`` and each seed's ``results.json``, so that
``toolimit reproduce --preset P --seed S --out OUT`` skips those cells and measures the rest.

    python scripts/restore_figure_cells.py benchmarks/results/figure_within_limits/results.json runs/figure
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from toolimit.artifacts import save_json
from toolimit.experiments.cells import Experiment
from toolimit.experiments.report import RESULTS_JSON, read_results
from toolimit.experiments.reproduce import seed_folder


def restore(results: Path, out: Path) -> int:
    """Write the cells of ``results`` (a ``results.json``) under ``out``; the number of cells written."""
    preset, runs = read_results(json.loads(results.read_text()))
    written = 0
    for seed, cells in runs.items():
        folder = seed_folder(out, seed)
        for cell in cells:
            key = Experiment(cell.tool, cell.world, cell.robot, Path(cell.demo)).cell_key(cell.method)
            save_json(folder / "cells" / f"{key}.json", cell.record())
            written += 1
        save_json(folder / RESULTS_JSON, {"preset": {**preset, "seed": seed}, "cells": []})
    return written


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, help="a committed results.json")
    parser.add_argument("out", type=Path, help="the reproduction's output folder")
    args = parser.parse_args()
    print(f"restored {restore(args.results, args.out)} cells into {args.out}")


if __name__ == "__main__":
    main()
