"""Every notebook in notebooks/ runs headless from top to bottom and is stored without outputs.

Each ``notebooks/*.ipynb`` (new ones are picked up automatically) is executed with nbclient in a
``python3`` kernel of this interpreter, working directory ``notebooks/``, with ``TOOLIMIT_QUICK=1``
so that the notebooks shrink their budgets, and with this checkout first on the kernel's
``PYTHONPATH`` (the kernel imports the ``toolimit`` under test, not another installed copy). A
failing cell fails the test with the cell's source and error. Each notebook must show at least one
inline figure (an SVG or HTML output), and weigh less than ``MAX_EXECUTED_BYTES`` executed.

To store a notebook without outputs: ``python tests/test_notebooks.py --strip notebooks/NAME.ipynb``.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

import nbformat
import pytest

REPO = Path(__file__).resolve().parents[1]
NOTEBOOKS_DIR = REPO / "notebooks"
NOTEBOOKS = sorted(NOTEBOOKS_DIR.glob("*.ipynb"))
#: Seconds one cell may run under TOOLIMIT_QUICK=1.
CELL_TIMEOUT_S = 300
#: Largest executed notebook, bytes: 3D views are linked files, not pages copied into the notebook.
MAX_EXECUTED_BYTES = 2_000_000
#: Output types that are an inline figure.
FIGURE_TYPES = ("image/svg+xml", "text/html")
#: Terminal colour codes in IPython tracebacks.
ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;]*m")


def strip_outputs(notebook: nbformat.NotebookNode) -> nbformat.NotebookNode:
    """The notebook with no outputs and no execution counts (what the repository stores)."""
    for cell in notebook.cells:
        if cell.cell_type == "code":
            cell.outputs = []
            cell.execution_count = None
    return notebook


def test_notebooks_exist():
    assert NOTEBOOKS, f"no notebook found in {NOTEBOOKS_DIR}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.name)
def test_notebook_is_stored_without_outputs(path):
    notebook = nbformat.read(path, as_version=4)
    nbformat.validate(notebook)
    dirty = [
        index for index, cell in enumerate(notebook.cells)
        if cell.cell_type == "code" and (cell.outputs or cell.execution_count is not None)
    ]
    assert not dirty, (
        f"{path.name}: code cells {dirty} have outputs or execution counts; "
        f"run `python tests/test_notebooks.py --strip {path.relative_to(NOTEBOOKS_DIR.parent)}`"
    )


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.name)
def test_notebook_runs_top_to_bottom(path, monkeypatch):
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError, CellTimeoutError

    monkeypatch.setenv("TOOLIMIT_QUICK", "1")
    monkeypatch.setenv("RERUN_NOTEBOOK_ASSET", "inline")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    notebook = nbformat.read(path, as_version=4)
    client = NotebookClient(
        notebook,
        timeout=CELL_TIMEOUT_S,
        kernel_name="python3",  # jupyter_client starts it with this interpreter (sys.executable)
        resources={"metadata": {"path": str(NOTEBOOKS_DIR)}},
    )
    failure = None
    try:
        client.execute()
    except (CellExecutionError, CellTimeoutError) as error:
        failure = ANSI_ESCAPE.sub("", str(error))
    if failure is not None:
        pytest.fail(f"{path.name} failed:\n{failure}", pytrace=False)
    size = len(nbformat.writes(notebook).encode())
    assert size < MAX_EXECUTED_BYTES, f"{path.name} weighs {size / 1e6:.1f} MB executed (limit 2 MB)"
    printed = "".join(output.get("text", "") for cell in notebook.cells for output in cell.get("outputs", []))
    assert "IProgress not found" not in printed, f"{path.name}: tqdm warns that ipywidgets is missing"
    figures = [
        kind
        for cell in notebook.cells
        for output in cell.get("outputs", [])
        for kind in output.get("data", {})
        if kind in FIGURE_TYPES
    ]
    assert figures, f"{path.name} shows no inline figure (SVG or HTML output)"


if __name__ == "__main__":
    if len(sys.argv) < 3 or sys.argv[1] != "--strip":
        sys.exit("usage: python tests/test_notebooks.py --strip NOTEBOOK.ipynb [...]")
    for name in sys.argv[2:]:
        nbformat.write(strip_outputs(nbformat.read(name, as_version=4)), name)
        print(f"stripped {name}")
