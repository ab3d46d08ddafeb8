"""Fixtures for the comparison tests: the benchmark's PROBLEM.md module (benchmarks/ is not a package)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest


@pytest.fixture(scope="session")
def trajopt_problem(repo_root: Path) -> ModuleType:
    """benchmarks/trajopt_problem.py, imported by path."""
    path = repo_root / "benchmarks" / "trajopt_problem.py"
    spec = importlib.util.spec_from_file_location("trajopt_problem", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("trajopt_problem", module)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def panda_on_base(trajopt_problem: ModuleType):
    return trajopt_problem.build_panda_on_base()


@pytest.fixture(scope="session")
def trajopt_benchmark(repo_root: Path, trajopt_problem: ModuleType) -> ModuleType:
    """benchmarks/trajopt_vs_crocoddyl.py, imported by path (it needs crocoddyl only when solving)."""
    path = repo_root / "benchmarks" / "trajopt_vs_crocoddyl.py"
    spec = importlib.util.spec_from_file_location("trajopt_vs_crocoddyl", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("trajopt_vs_crocoddyl", module)  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module
