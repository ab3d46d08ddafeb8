"""The grading fixture: import a student's exercise module from the chosen submission folder.

The folder is ``$TOOLIMIT_SUBMISSION`` (a path, relative to the current directory or absolute);
without it, the stubs in ``course/exercises``. Every grader asks for its module with
``submission("exNN_name")`` and calls the functions on it; the returned object turns the usual
student mistakes (missing file, syntax error, function not written yet, an exception, a call that
never returns) into one readable failure, and refuses a submission that calls an existing
implementation of its exercise (the grader's ``FORBIDDEN`` list, plus the course's solutions and
graders; see ``grading.py``).

Each student call runs under a time limit (``$TOOLIMIT_CALL_TIME_LIMIT`` seconds, default 20, or
the grader's ``CALL_TIME_LIMIT_S``); after one call ran out of time, the exercise's later calls fail
at once. With ``$TOOLIMIT_GRADE_REPORT`` set, every test's outcome is appended to that file as a
JSON line (``course/grade.py`` reads it).
"""

from __future__ import annotations

import functools
import importlib.util
import json
import os
import traceback
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
from grading import (
    CallTimer,
    Forbidden,
    ForbiddenUse,
    Guard,
    ImportFailed,
    MissingFile,
    NotWritten,
    TooSlow,
    _Stop,
    fail,
    static_violations,
)

SUBMISSION_ENV = "TOOLIMIT_SUBMISSION"
CALL_LIMIT_ENV = "TOOLIMIT_CALL_TIME_LIMIT"
REPORT_ENV = "TOOLIMIT_GRADE_REPORT"
DEFAULT_SUBMISSION = Path(__file__).resolve().parents[1] / "exercises"
DEFAULT_CALL_TIME_LIMIT_S = 20.0


def submission_folder() -> Path:
    """The folder holding the student's ``exNN_name.py`` files."""
    chosen = os.environ.get(SUBMISSION_ENV)
    return Path(chosen).resolve() if chosen else DEFAULT_SUBMISSION


def forbidden_message(path: Path, uses: list[str]) -> str:
    return (
        f"0 points for this exercise: {path.name} uses {'; '.join(uses[:3])}. The grader refuses an existing "
        "implementation of the function you are asked to write (the library's, a dependency's, the course's "
        "solutions or graders) and what would hide one (other processes, replacing the profiler). Write it "
        "yourself: the other toolimit names (ToolDemo, RobotModel, ...) and numpy, scipy and torch building blocks "
        "stay allowed."
    )


def _student_line(error: BaseException, path: Path) -> str:
    """``line 12`` of the student's file where the exception passed last, or ''."""
    lines = [frame.lineno for frame in traceback.extract_tb(error.__traceback__) if Path(frame.filename) == path]
    return f" (line {lines[-1]} of {path.name})" if lines else ""


class StudentModule:
    """A student's module whose functions fail the test with a clear message when unfinished,
    failing, too slow, or calling a forbidden implementation."""

    def __init__(self, module: ModuleType, path: Path, forbidden: Forbidden, time_limit: float, hint: str = "") -> None:
        self._module = module
        self._hint = hint
        self._path = path
        self._forbidden = forbidden
        self._time_limit = time_limit
        self._blocked: Exception | None = None  # a verdict every later call repeats

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        if self._blocked is not None:
            raise type(self._blocked)(str(self._blocked))
        if not hasattr(self._module, name):
            fail(f"{self._path} has no function `{name}`: keep the name and signature of the stub")
        value = getattr(self._module, name)
        if not callable(value):
            return value

        @functools.wraps(value)
        def call(*args: Any, **kwargs: Any) -> Any:
            if self._blocked is not None:
                raise type(self._blocked)(str(self._blocked))
            guard, timer, error = Guard(self._forbidden), CallTimer(self._time_limit), None
            try:
                with guard, timer:
                    result = materialised(value(*args, **kwargs))
            except (Exception, _Stop) as raised:
                error = raised
            if guard.violation or guard.tampered:
                use = guard.violation or "sys.setprofile (the grader's watch was switched off)"
                self._blocked = ForbiddenUse(forbidden_message(self._path, [use]))
                raise self._blocked
            if timer.expired:
                self._blocked = TooSlow(
                    f"`{name}` did not return within {self._time_limit:g} s (an endless loop?); "
                    f"the exercise's later calls are not run{self._hint}"
                )
                raise self._blocked
            if isinstance(error, NotImplementedError):
                raise NotWritten(f"`{name}` in {self._path} is not written yet (it raises NotImplementedError)")
            if error is not None:
                message = str(error).strip().splitlines()[0] if str(error).strip() else ""
                fail(f"`{name}` raised {type(error).__name__}: {message}{_student_line(error, self._path)}")
            return result

        return call


def materialised(result: Any) -> Any:
    """The result with lazy parts computed now, under the guard: an iterator becomes a list, an
    object that only converts to an array (``__array__``) becomes the array; tuples and lists
    element by element. Arrays, tensors, numbers and None are returned as they are."""
    if isinstance(result, (tuple, list)):
        return type(result)(materialised(item) for item in result)
    if result is None or isinstance(result, (np.ndarray, np.generic, int, float, complex, bool, str)):
        return result
    if type(result).__module__.split(".")[0] == "torch":
        return result
    if hasattr(result, "__next__"):
        return [materialised(item) for item in result]
    if hasattr(result, "__array__"):
        return np.asarray(result)
    return result


def call_time_limit(grader: ModuleType | None) -> float:
    if os.environ.get(CALL_LIMIT_ENV):
        return float(os.environ[CALL_LIMIT_ENV])
    return float(getattr(grader, "CALL_TIME_LIMIT_S", DEFAULT_CALL_TIME_LIMIT_S))


@functools.cache
def load_submission(
    module_name: str,
    forbidden_names: tuple[str, ...] = (),
    time_limit: float = DEFAULT_CALL_TIME_LIMIT_S,
    hint: str = "",
) -> StudentModule:
    """Import ``<folder>/<module_name>.py`` under a private name (so solutions never clash),
    under the guard, then read its source for forbidden names."""
    folder = submission_folder()
    path = folder / f"{module_name}.py"
    if not path.is_file():
        raise MissingFile(f"no file {module_name}.py in the submission folder {folder} (set ${SUBMISSION_ENV})")
    forbidden = Forbidden(forbidden_names, path)
    private_name = f"_submission_{abs(hash(str(path)))}_{module_name}"
    spec = importlib.util.spec_from_file_location(private_name, path)
    module = importlib.util.module_from_spec(spec)
    guard, timer, error = Guard(forbidden), CallTimer(time_limit), None
    try:
        with guard, timer:
            spec.loader.exec_module(module)
    except (Exception, _Stop) as raised:
        error = raised
    student = StudentModule(module, path, forbidden, time_limit, hint)
    uses = [guard.violation] if guard.violation else []
    if error is not None and not uses:
        if timer.expired:
            raise TooSlow(f"importing {path.name} did not finish within {time_limit:g} s")
        raise ImportFailed(f"{path} cannot be imported: {type(error).__name__}: {error}")
    uses += static_violations(path.read_text(), forbidden)
    if uses:
        student._blocked = ForbiddenUse(forbidden_message(path, uses))
    return student


@pytest.fixture
def submission(request) -> Callable[[str], StudentModule]:
    """``submission("ex01_velocity_keypoints")`` -> the student's module (imported once per session),
    guarded by the calling grader's ``FORBIDDEN`` list."""
    forbidden = tuple(getattr(request.module, "FORBIDDEN", ()))
    limit = call_time_limit(request.module)
    hint = getattr(request.module, "TOO_SLOW_HINT", "")

    def load(module_name: str) -> StudentModule:
        try:
            return load_submission(module_name, forbidden, limit, hint)
        except (MissingFile, ImportFailed, TooSlow) as verdict:
            raise type(verdict)(str(verdict)) from None

    return load


# --- the report grade.py reads -------------------------------------------------------------------
def _write(record: dict) -> None:
    path = os.environ.get(REPORT_ENV)
    if path:
        with open(path, "a", encoding="utf-8") as stream:
            stream.write(json.dumps(record) + "\n")


def pytest_collection_finish(session: pytest.Session) -> None:
    _write({"collected": len(session.items)})


def pytest_collectreport(report: pytest.CollectReport) -> None:
    if report.failed:
        _write({"test": report.nodeid, "when": "collect", "outcome": "error", "message": report.longreprtext[-2000:]})


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    outcome = yield
    report = outcome.get_result()
    if call.excinfo is not None:
        report.user_properties.append(("verdict", getattr(call.excinfo.value, "verdict", "failed")))


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if report.passed and report.when != "call":
        return
    verdicts = [value for key, value in report.user_properties if key == "verdict"]
    _write(
        {
            "test": report.nodeid,
            "when": report.when,
            "outcome": report.outcome,
            "verdict": verdicts[-1] if verdicts else None,
            "message": "" if report.passed else report.longreprtext[-2000:],
        }
    )
