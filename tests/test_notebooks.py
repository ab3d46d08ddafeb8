"""Every notebook in notebooks/ runs headless from top to bottom and is stored without outputs.

Each ``notebooks/*.ipynb`` (new ones are picked up automatically) is executed with nbclient in a
``python3`` kernel of this interpreter, working directory ``notebooks/``, with ``TOOLIMIT_QUICK=1``
so that the notebooks shrink their budgets, and with this checkout first on the kernel's
``PYTHONPATH`` (the kernel imports the ``toolimit`` under test, not another installed copy). A
failing cell fails the test with the cell's source and error. Each notebook must show at least one
inline figure (an SVG or HTML output), and weigh less than ``MAX_EXECUTED_BYTES`` executed.

A notebook with course exercises runs with the reference answers of its marked cells filled in
(``### BEGIN SOLUTION``): each exercise's check must print that it passed.

A number the text quotes from the notebook's own output is marked in the markdown as
``<span class="printed">0.07</span>`` (rendered as plain text): the executed notebook must print it
(as a whole number token: ``0.5`` is not found in ``0.51``). Mark only what any run prints, whatever
the budget and whether ``../shared`` is present.

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
#: A number the text quotes from the notebook's own output (module docstring).
PRINTED_MARK = re.compile(r'<span class="printed">([^<]+)</span>')
#: A course exercise's reference answer in a code cell (course/grade.py strips it from the student
#: bundle); each is followed by a check that prints the verdict below.
SOLUTION_MARK = "### BEGIN SOLUTION"
EXERCISE_PASSED = re.compile(r"^[\w -]+: exercise passed$", re.MULTILINE)
#: Terminal colour codes in IPython tracebacks.
ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;]*m")


def strip_outputs(notebook: nbformat.NotebookNode) -> nbformat.NotebookNode:
    """The notebook with no outputs and no execution counts (what the repository stores)."""
    for cell in notebook.cells:
        if cell.cell_type == "code":
            cell.outputs = []
            cell.execution_count = None
    return notebook


def output_text(notebook: nbformat.NotebookNode) -> str:
    """Everything the code cells printed or returned as text."""
    return "\n".join(
        output.get("text", "") or output.get("data", {}).get("text/plain", "")
        for cell in notebook.cells
        for output in cell.get("outputs", [])
    )


def unprinted_claims(notebook: nbformat.NotebookNode) -> list[str]:
    """The marked numbers of the markdown cells that no output of ``notebook`` prints."""
    printed = output_text(notebook)
    return [
        claim
        for cell in notebook.cells
        if cell.cell_type == "markdown"
        for claim in PRINTED_MARK.findall(cell.source)
        if not re.search(rf"(?<![\w.]){re.escape(claim.strip())}(?!\w)", printed)
    ]


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
    assert "IProgress not found" not in output_text(notebook), f"{path.name}: tqdm warns that ipywidgets is missing"
    exercises = sum(cell.cell_type == "code" and SOLUTION_MARK in cell.source for cell in notebook.cells)
    passed = EXERCISE_PASSED.findall(output_text(notebook))
    assert len(passed) == exercises, (
        f"{path.name}: {exercises} exercises with their reference answers, {len(passed)} checks passed"
    )
    unprinted = unprinted_claims(notebook)
    assert not unprinted, f"{path.name}: the text quotes {unprinted} as printed, but no output prints them"
    figures = [
        kind
        for cell in notebook.cells
        for output in cell.get("outputs", [])
        for kind in output.get("data", {})
        if kind in FIGURE_TYPES
    ]
    assert figures, f"{path.name} shows no inline figure (SVG or HTML output)"
    executed = os.environ.get("TOOLIMIT_DOCS_EXECUTED_NOTEBOOKS")
    if executed:  # the documentation renders this execution instead of running the notebook again
        nbformat.write(notebook, Path(executed) / path.name)


def test_a_marked_number_must_be_printed_as_a_whole_token():
    notebook = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_markdown_cell('clip <span class="printed">0.5</span>, <span class="printed">200</span> spheres'),
            nbformat.v4.new_code_cell("", outputs=[nbformat.v4.new_output("stream", text="max_grad_norm 0.51, 200 spheres")]),
        ]
    )
    assert unprinted_claims(notebook) == ["0.5"]
    notebook.cells[1].outputs[0].text += "\nclip 0.5."
    assert unprinted_claims(notebook) == []


if __name__ == "__main__":
    if len(sys.argv) < 3 or sys.argv[1] != "--strip":
        sys.exit("usage: python tests/test_notebooks.py --strip NOTEBOOK.ipynb [...]")
    for name in sys.argv[2:]:
        nbformat.write(strip_outputs(nbformat.read(name, as_version=4)), name)
        print(f"stripped {name}")
