"""The grading fixture: import a student's exercise module from the chosen submission folder.

The folder is ``$TOOLIMIT_SUBMISSION`` (a path, relative to the current directory or absolute);
without it, the stubs in ``course/exercises``. Every grader asks for its module with
``submission("exNN_name")`` and calls the functions on it; the returned object turns the usual
student mistakes (missing file, syntax error, function not written yet) into one readable failure.
"""

from __future__ import annotations

import functools
import importlib.util
import os
from pathlib import Path
from types import ModuleType
from typing import Any, Callable

import pytest

SUBMISSION_ENV = "TOOLIMIT_SUBMISSION"
DEFAULT_SUBMISSION = Path(__file__).resolve().parents[1] / "exercises"


def submission_folder() -> Path:
    """The folder holding the student's ``exNN_name.py`` files."""
    chosen = os.environ.get(SUBMISSION_ENV)
    return Path(chosen).resolve() if chosen else DEFAULT_SUBMISSION


class StudentModule:
    """A student's module whose functions fail the test with a clear message when unfinished."""

    def __init__(self, module: ModuleType, path: Path) -> None:
        self._module = module
        self._path = path

    def __getattr__(self, name: str) -> Any:
        if not hasattr(self._module, name):
            pytest.fail(f"{self._path} has no function `{name}`: keep the name and signature of the stub", pytrace=False)
        value = getattr(self._module, name)
        if not callable(value):
            return value

        @functools.wraps(value)
        def call(*args: Any, **kwargs: Any) -> Any:
            try:
                return value(*args, **kwargs)
            except NotImplementedError:
                message = f"`{name}` in {self._path} is not written yet (it raises NotImplementedError)"
                raise pytest.fail.Exception(message, pytrace=False) from None

        return call


def load_submission(module_name: str, folder: Path | None = None) -> StudentModule:
    """Import ``<folder>/<module_name>.py`` under a private name (so solutions never clash)."""
    folder = submission_folder() if folder is None else folder
    path = folder / f"{module_name}.py"
    if not path.is_file():
        pytest.fail(f"no file {module_name}.py in the submission folder {folder} (set ${SUBMISSION_ENV})", pytrace=False)
    private_name = f"_submission_{abs(hash(str(path)))}_{module_name}"
    spec = importlib.util.spec_from_file_location(private_name, path)
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as error:  # the student's file does not even import: say why, in one line
        message = f"{path} cannot be imported: {type(error).__name__}: {error}"
        raise pytest.fail.Exception(message, pytrace=False) from None
    return StudentModule(module, path)


@pytest.fixture(scope="session")
def submission() -> Callable[[str], StudentModule]:
    """``submission("ex01_velocity_keypoints")`` -> the student's module (imported once per session)."""
    return functools.cache(load_submission)
