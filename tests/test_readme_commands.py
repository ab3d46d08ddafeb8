"""Every command README.md tells a user to type is checked, and the cheap ones are run.

Each line of the README's ``bash`` blocks is split at ``&&`` into commands (a trailing ``# comment``
dropped). Every command must be one this test knows how to check, so a new kind of command in the
README fails here until it is covered:

- ``toolimit ...``: its flags parse with the command's own parser; the Quick start's ``toolimit run``
  is run on ``--quick`` budgets, and the commands that read its output (``python -m json.tool``)
  are run on what it wrote;
- ``pip install ...``: every extra named exists in pyproject.toml, and a pinned package is pinned to
  the same version there;
- ``pytest PATHS``, ``sphinx-build ... SOURCE OUT``: the paths exist (the suite and the site's build
  run in CI, not from inside a test);
- ``python3 -m venv``, ``. .venv/bin/activate``, ``git clone``, ``cd``: the form is checked.
"""

from __future__ import annotations

import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from packaging.requirements import Requirement

from toolimit.cli import build_parser, main

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: pytest's own dependency
    import tomli as tomllib

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
#: The folder the Quick start's run writes (the README's own output path).
QUICK_START_OUT = "runs/spade_planar"


def readme_commands() -> list[list[str]]:
    """Every command of the README's ``bash`` blocks, as argument lists, in order."""
    text = README.read_text(encoding="utf-8")
    commands = []
    for block in re.findall(r"```bash\n(.*?)```", text, re.S):
        for line in block.splitlines():
            line = re.sub(r"\s+#.*$", "", line).strip()
            commands += [shlex.split(part) for part in line.split("&&") if part.strip()]
    return commands


def pyproject() -> dict:
    return tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))


def test_the_readme_has_the_quick_start_and_the_docs_build():
    commands = readme_commands()
    assert any(c[:2] == ["toolimit", "run"] for c in commands)
    assert any(c[0] == "sphinx-build" for c in commands), "the Development section names the docs build"


@pytest.mark.parametrize("argv", [c for c in readme_commands() if c[0] == "toolimit"], ids=" ".join)
def test_toolimit_flags_parse(argv: list[str]):
    build_parser().parse_args(argv[1:])  # SystemExit (exit 2) on a bad flag fails the test


@pytest.mark.parametrize("argv", [c for c in readme_commands() if c[0] == "pip"], ids=" ".join)
def test_pip_installs_what_pyproject_declares(argv: list[str]):
    assert argv[1] == "install"
    project = pyproject()["project"]
    pins = {re.split(r"[=<>!~ ]", dep, maxsplit=1)[0]: dep for dep in project["dependencies"]}
    targets = iter(argv[2:])
    for target in targets:
        if target == "-e":
            continue
        if target in ("-c", "--constraint", "-r", "--requirement"):
            assert (REPO / next(targets)).is_file(), f"{target} names a file the repository does not hold"
            continue
        extras = re.fullmatch(r"\.(?:\[([\w,-]+)\])?", target)
        if extras:
            for extra in filter(None, (extras.group(1) or "").split(",")):
                assert extra in project["optional-dependencies"], f"README installs an unknown extra [{extra}]"
        else:  # a package named on its own: one pyproject declares, at a version its range admits
            requirement = Requirement(target)
            assert requirement.name in pins, f"README installs {requirement.name}, which pyproject does not declare"
            declared = Requirement(pins[requirement.name]).specifier
            pinned = [spec.version for spec in requirement.specifier if spec.operator == "=="]
            assert len(pinned) == 1 and declared.contains(pinned[0]), (
                f"{target} is not one version within pyproject's {pins[requirement.name]}"
            )


@pytest.mark.parametrize(
    "argv",
    [c for c in readme_commands() if c[0] in {"python3", ".", "git", "cd", "pytest", "sphinx-build", "python"}],
    ids=" ".join,
)
def test_other_commands_have_their_form(argv: list[str]):
    name = argv[0]
    if name == "python3":
        assert argv[1:3] == ["-m", "venv"] and argv[3] == ".venv"
    elif name == ".":
        assert argv[1:] == [".venv/bin/activate"]
    elif name == "git":
        assert argv[1] == "clone" and argv[2].endswith("/toolimit.git")
    elif name == "cd":
        assert argv[1:] == ["toolimit"]
    elif name == "pytest":
        assert all((REPO / path).exists() for path in argv[1:] if not path.startswith("-"))
    elif name == "sphinx-build":
        assert "-W" in argv, "the docs build treats warnings as errors"
        source = argv[-2]
        assert (REPO / source / "conf.py").is_file()
    else:
        assert argv[1:3] == ["-m", "json.tool"] and argv[3].startswith(QUICK_START_OUT + "/")


def test_every_command_is_checked():
    known = {"toolimit", "pip", "python3", ".", "git", "cd", "pytest", "sphinx-build", "python"}
    unknown = [" ".join(c) for c in readme_commands() if c[0] not in known]
    assert not unknown, f"README commands this test does not check: {unknown}"


def test_the_quick_start_run_and_what_reads_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """The Quick start's ``toolimit run`` on quick budgets, then the README's commands on its output."""
    monkeypatch.chdir(REPO)
    (run,) = [c for c in readme_commands() if c[:2] == ["toolimit", "run"]]
    assert run[run.index("--out") + 1] == QUICK_START_OUT
    out = tmp_path / QUICK_START_OUT
    argv = [str(out) if arg == QUICK_START_OUT else arg for arg in run[1:]]
    assert main([*argv, "--quick", "--quiet"]) == 0
    readers = [c for c in readme_commands() if c[0] == "python"]
    assert readers, "the README shows how to look at the first run's result"
    for reader in readers:
        path = tmp_path / reader[3]
        shown = subprocess.run(
            [sys.executable, *reader[1:3], str(path)], cwd=REPO, capture_output=True, text=True, check=True
        )
        assert "success_rate" in json.loads(shown.stdout)
