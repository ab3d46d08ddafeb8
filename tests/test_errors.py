"""The error family: every kind is a ToolimitError (and still the built-in it replaced); the command
line answers exactly those (and OSError) with one line and exit 2, and lets a bug's traceback through."""

import sys
import types

import pytest

from toolimit import cli
from toolimit.errors import (
    BaseInsideFootprint,
    DemoError,
    InputError,
    InvalidLearningConfig,
    InvalidSceneParameters,
    PathOutsideLimits,
    SolverFailure,
    ToolimitError,
)


@pytest.mark.parametrize("kind, builtin", [
    (InputError, ValueError), (DemoError, ValueError), (InvalidSceneParameters, ValueError),
    (BaseInsideFootprint, ValueError), (PathOutsideLimits, ValueError), (SolverFailure, RuntimeError),
    (cli.CliError, ValueError), (InvalidLearningConfig, ValueError),
])
def test_every_kind_is_a_toolimit_error_and_its_builtin(kind, builtin):
    assert issubclass(kind, ToolimitError) and issubclass(kind, builtin)


def _cli_raising(monkeypatch, error: BaseException) -> None:
    """Make `toolimit boom` a command that raises ``error``."""
    module = types.ModuleType("toolimit_test_boom")

    def register(subparsers):
        parser = subparsers.add_parser("boom")
        parser.set_defaults(func=lambda args: (_ for _ in ()).throw(error))

    module.register = register
    monkeypatch.setitem(sys.modules, module.__name__, module)
    monkeypatch.setattr(cli, "COMMANDS", (module.__name__,))


@pytest.mark.parametrize("error", [
    DemoError("demo.npz: key 'head' has NaN"), InvalidSceneParameters("box outside the world"),
    BaseInsideFootprint("base inside element 0"), PathOutsideLimits("joint 1 at sample 3"),
    SolverFailure("OSQP failed"), FileNotFoundError("x.npz: no such file"),
])
def test_cli_answers_the_error_family_with_one_line_and_exit_2(monkeypatch, capsys, error):
    _cli_raising(monkeypatch, error)
    assert cli.main(["boom"]) == 2
    err = capsys.readouterr().err
    assert err == f"toolimit boom: error: {error}\n"


@pytest.mark.parametrize("error", [ValueError("shapes (3,) and (4,) do not match"), KeyError("q"),
                                   RuntimeError("bug")])
def test_cli_lets_a_library_bug_show_its_traceback(monkeypatch, error):
    _cli_raising(monkeypatch, error)
    with pytest.raises(type(error)):
        cli.main(["boom"])
