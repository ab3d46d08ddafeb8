"""What a user reaches from the package roots: ``toolimit.<stage>`` and each stage's ``__all__``."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

import toolimit

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("name", toolimit.SUBPACKAGES)
def test_every_exported_name_of_a_subpackage_resolves(name):
    package = importlib.import_module(f"toolimit.{name}")
    assert getattr(toolimit, name) is package
    missing = [export for export in getattr(package, "__all__", ()) if not hasattr(package, export)]
    assert not missing, f"toolimit.{name}.__all__ names what it does not define: {missing}"


def test_the_stage_entry_points_are_exported_by_their_roots():
    assert {"learn_policy", "LearningConfig", "LearningOutcome", "load_policy", "evaluate", "Evaluation"} <= set(
        toolimit.learn.__all__
    )
    assert toolimit.learn.learn_policy.__module__ == "toolimit.learn.training"
    assert toolimit.learn.evaluate.__module__ == "toolimit.learn.evaluate"
    assert "select_by_robot_execution" in toolimit.trajopt.__all__


def test_import_toolimit_loads_no_stage_and_an_attribute_loads_its_stage():
    """In a fresh interpreter: ``import toolimit`` alone loads neither a subpackage nor torch;
    ``toolimit.demos`` then imports the subpackage."""
    code = (
        "import sys, toolimit\n"
        "loaded = sorted(m for m in sys.modules if m.startswith('toolimit.') or m in ('torch', 'pinocchio'))\n"
        "assert not loaded, loaded\n"
        "assert 'demos' in dir(toolimit) and 'demos' not in vars(toolimit)\n"
        "print(toolimit.demos.ToolDemo.__module__, 'toolimit.demos' in sys.modules)\n"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=REPO)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["toolimit.demos.tool_demo", "True"]


def test_an_unknown_attribute_is_an_attribute_error():
    with pytest.raises(AttributeError, match="module 'toolimit' has no attribute 'cli_tools'"):
        toolimit.cli_tools  # noqa: B018
    assert not hasattr(toolimit, "demo")
