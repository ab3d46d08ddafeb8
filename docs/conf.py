"""Sphinx configuration of toolimit's documentation site.

Build: ``sphinx-build -W --keep-going -b html docs docs/_build/html`` (the ``docs`` extra). Pages are
MyST markdown; ``notebooks/`` (linked as ``docs/notebooks``) is executed during the build on the
notebooks' quick budgets (``TOOLIMIT_QUICK=1``) by myst-nb; the API reference comes from the
docstrings (autodoc, napoleon for the Google sections, autosummary); the command line's reference
from its argparse parsers (``docs/_ext/cli_reference.py``); the results pages' charts from the committed JSON
(``docs/_ext/results_charts.py``). Nothing is fetched from the network: the theme's fonts are the
system's, and no page loads a script from elsewhere.

``TOOLIMIT_DOCS_EXECUTE`` chooses how notebooks are executed: ``force`` (default, what CI does),
``cache`` (re-run only notebooks that changed) or ``off`` (render them without outputs, e.g. while
writing a page). ``TOOLIMIT_DOCS_EXECUTED_NOTEBOOKS`` names a folder of notebooks already executed
on the quick budgets (e.g. by the test suite): a notebook found there, with the same cells as
``notebooks/``, is rendered with its outputs instead of being executed again.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
REPO = DOCS.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(DOCS / "_ext"))
# The notebooks' kernels import this checkout and run on the quick budgets, offline (as tests/test_notebooks.py).
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))
os.environ.setdefault("TOOLIMIT_QUICK", "1")
os.environ.setdefault("RERUN_NOTEBOOK_ASSET", "inline")  # rerun's viewer from the wheel, not a CDN

import toolimit  # noqa: E402

project = "toolimit"
author = "the toolimit contributors"
copyright = "2026, the toolimit contributors"
release = version = toolimit.__version__

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "cli_reference",
    "results_charts",
]
# notebooks/runs: what the notebooks write when executed (their runs), not pages.
exclude_patterns = ["_build", "**/.ipynb_checkpoints", "notebooks/runs", "Thumbs.db", ".DS_Store"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}

# MyST: heading anchors so that [text](page.md#section) links resolve (and are checked).
myst_heading_anchors = 4
myst_enable_extensions = ["colon_fence"]

# Notebooks: executed in their own folder (they read ../data), each cell within 5 minutes.
nb_execution_mode = os.environ.get("TOOLIMIT_DOCS_EXECUTE", "force")
nb_execution_timeout = 300
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_execution_in_temp = False
nb_merge_streams = True

# API reference: every public module, its docstrings in Google style.
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_ivar = True
# Members inherit no docstring from their bases (gymnasium, torch): the reference shows ours.
autodoc_inherit_docstrings = False
# Optional extras: the API pages of the modules that need them are built without them.
autodoc_mock_imports = ["ray", "crocoddyl", "cv2"]

html_theme = "furo"
html_title = f"toolimit {release}"
html_static_path: list[str] = []
# No page loads a script from the network (the site is read offline and checked in CI): the pages
# hold no math, and should one, MathJax is looked for beside the site, not on a CDN (the browser
# test then reports the missing file).
mathjax_path = "mathjax/tex-chtml.js"


def _plain_bars(app, what, name, obj, options, lines: list[str]) -> None:  # noqa: ANN001
    """Docstrings write |x| for a magnitude, not a reStructuredText substitution: escape each bar
    outside inline literals."""
    for index, line in enumerate(lines):
        parts = line.split("``")
        lines[index] = "``".join(part if k % 2 else part.replace("|", r"\|") for k, part in enumerate(parts))


#: Shown at the top of every notebook's page: its figures come from the quick budgets.
QUICK_BUDGET_NOTE = (
    '<div class="admonition note quick-budget"><p class="admonition-title">Quick budgets</p><p>This notebook was '
    "executed while the site was built, with <code>TOOLIMIT_QUICK=1</code>: its learning and search budgets are "
    "a few seconds' worth, so its figures show each stage at work, not what a full run achieves (the "
    '<a href="../results/index.html">results</a> do). Run it at its default budgets with <code>jupyter lab '
    "notebooks/</code>.</p></div>"
)


def _label_quick_budget_figures(app, pagename: str, templatename: str, context: dict, doctree) -> None:  # noqa: ANN001
    """Every notebook page says its outputs were made on the quick budgets."""
    if pagename.startswith("notebooks/") and "body" in context:
        context["body"] = QUICK_BUDGET_NOTE + context["body"]


def _use_executed_notebook(app, docname: str, source: list[str]) -> None:  # noqa: ANN001
    """A notebook executed already (``TOOLIMIT_DOCS_EXECUTED_NOTEBOOKS``) replaces the stored one's
    text, marked not to be executed again; it must hold the stored notebook's cells, else the build
    stops (an execution of another version of the notebook would show outputs it does not make)."""
    folder = os.environ.get("TOOLIMIT_DOCS_EXECUTED_NOTEBOOKS")
    if not folder or not docname.startswith("notebooks/"):
        return
    import nbformat
    from sphinx.errors import ExtensionError

    path = Path(folder) / f"{Path(docname).name}.ipynb"
    if not path.is_file():
        return  # executed during the build
    executed = nbformat.reads(path.read_text(encoding="utf-8"), as_version=4)
    stored = nbformat.reads(source[0], as_version=4)
    if [cell.source for cell in executed.cells] != [cell.source for cell in stored.cells]:
        raise ExtensionError(f"{path}: its cells are not those of notebooks/{path.name}; execute it again")
    executed.metadata.setdefault("mystnb", {})["execution_mode"] = "off"
    source[0] = nbformat.writes(executed)


def setup(app) -> None:  # noqa: ANN001
    app.connect("autodoc-process-docstring", _plain_bars)
    app.connect("html-page-context", _label_quick_budget_figures)
    app.connect("source-read", _use_executed_notebook)
