"""The grading fixture: the student's exercise module, run in a process of its own.

The folder is ``$TOOLIMIT_SUBMISSION`` (a path, relative to the current directory or absolute);
without it, the stubs in ``course/exercises``. Every grader asks for its module with
``submission("exNN_name")`` and calls the functions on it: each call sends the inputs to the
student's process (``student_process.py``) and returns the outputs it sent back, decoded as plain
values (``isolation.py``), so the student's code never runs in this process. The returned object
turns the usual student mistakes (missing file, syntax error, function not written yet, an
exception, a call that never returns, a crash) into one readable failure, and refuses a submission
that calls an existing implementation of its exercise (the grader's ``FORBIDDEN`` list, plus the
course's solutions and graders; the guard runs in the student's process, see ``grading.py``). A
grader's own error on a value it received becomes one message naming what the function returns
(the grader's ``RETURNS``).

Each student call runs under a time limit (``$TOOLIMIT_CALL_TIME_LIMIT`` seconds, default 20, or
the grader's ``CALL_TIME_LIMIT_S``): the student's process stops it, or is killed
``KILL_MARGIN_S`` later; after one call ran out of time, the exercise's later calls fail at once.
With ``$TOOLIMIT_GRADE_REPORT`` set, every test's outcome is appended to that file as a JSON line
(``course/grade.py`` reads it).
"""

from __future__ import annotations

import functools
import json
import os
import pickle
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from grading import ForbiddenUse, ImportFailed, MissingFile, NotWritten, TooSlow, fail
from isolation import ChannelClosed, decode, keep_memory_private, loads, receive, send

SUBMISSION_ENV = "TOOLIMIT_SUBMISSION"
CALL_LIMIT_ENV = "TOOLIMIT_CALL_TIME_LIMIT"
REPORT_ENV = "TOOLIMIT_GRADE_REPORT"
DEFAULT_SUBMISSION = Path(__file__).resolve().parents[1] / "exercises"
DEFAULT_CALL_TIME_LIMIT_S = 20.0
STUDENT_PROCESS = Path(__file__).resolve().parent / "student_process.py"
#: seconds for the student's process to import what the exercise needs (torch, stable-baselines3)
STARTUP_TIME_S = 120.0
#: seconds past a call's limit before the grader kills a student's process that did not stop itself
KILL_MARGIN_S = 10.0
PROCESSES: list[StudentProcess] = []
RECEIVED: list[str] = []  # the functions whose values the running test received

keep_memory_private()  # the student's process cannot read this one's memory or environment


def submission_folder() -> Path:
    """The folder holding the student's ``exNN_name.py`` files."""
    chosen = os.environ.get(SUBMISSION_ENV)
    return Path(chosen).resolve() if chosen else DEFAULT_SUBMISSION


def forbidden_message(path: Path, uses: list[str]) -> str:
    return (
        f"0 points for this exercise: {path.name} uses {'; '.join(uses[:3])}. The grader refuses an existing "
        "implementation of the function you are asked to write (the library's, a dependency's, the course's "
        "solutions or graders) and what would hide one (threads, other processes, replacing the profiler). Write it "
        "yourself: the other toolimit names (ToolDemo, RobotModel, ...) and numpy, scipy and torch building blocks "
        "stay allowed."
    )


def student_environment() -> dict[str, str]:
    """The student's process's environment: what Python needs, nothing of the grader's (no report
    file, no case seed); one thread for numpy and torch."""
    kept = ("PATH", "HOME", "LANG", "LC_ALL", "PYTHONPATH", "VIRTUAL_ENV", "TMPDIR", "SYSTEMROOT", "TOOLIMIT_QUICK")
    env = {name: os.environ[name] for name in kept if name in os.environ}
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        env[name] = "1"
    return env


class StudentProcess:
    """The student's module in its own process (``student_process.py``): calls go out as inputs and
    come back as values (``isolation.py``)."""

    def __init__(self, path: Path, forbidden: tuple[str, ...], preload: tuple[str, ...], time_limit: float) -> None:
        self.path = path
        self.time_limit = time_limit
        self.spec = json.dumps(
            {"path": str(path), "forbidden": list(forbidden), "preload": list(preload), "time_limit": time_limit}
        )
        self.process: subprocess.Popen | None = None
        self.ready: dict = {}

    def start(self) -> dict:
        """Start the process and import the module; its first message (status ready, forbidden,
        import_error or too_slow)."""
        self.workdir = tempfile.TemporaryDirectory(prefix="student_")
        self.process = subprocess.Popen(
            [sys.executable, str(STUDENT_PROCESS), self.spec],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env=student_environment(),
            cwd=self.workdir.name,
        )
        # the imports (torch: seconds on a loaded machine) and the student's module's own time limit
        self.ready = self.receive(STARTUP_TIME_S + self.time_limit)
        return self.ready

    def receive(self, timeout_s: float) -> dict:
        assert self.process is not None and self.process.stdout is not None
        try:
            return loads(receive(self.process.stdout.fileno(), timeout_s))
        except TimeoutError:
            self.stop()
            return {"status": "killed_too_slow"}
        except (ChannelClosed, ValueError):
            code = self.process.poll()
            self.stop()
            return {"status": "ended", "code": code}

    def call(self, function: str, args: tuple, kwargs: dict, gradients: bool) -> dict:
        if self.process is None or self.process.poll() is not None:
            status = self.start()
            if status.get("status") != "ready":
                return status
        assert self.process is not None and self.process.stdin is not None
        request = pickle.dumps({"function": function, "args": args, "kwargs": kwargs, "gradients": gradients})
        try:
            send(self.process.stdin.fileno(), request)
        except OSError:
            code = self.process.poll()
            self.stop()
            return {"status": "ended", "code": code}
        # the student's process stops a call at the limit itself; this margin covers one that hides
        # from its timer (catching every exception)
        return self.receive(self.time_limit + KILL_MARGIN_S)

    def stop(self) -> None:
        if self.process is not None:
            if self.process.poll() is None:
                self.process.kill()
            self.process.wait()
            for stream in (self.process.stdin, self.process.stdout):
                if stream is not None:
                    stream.close()
            self.process = None


class StudentModule:
    """A student's module in its own process, whose functions fail the test with a clear message
    when unfinished, failing, too slow, or calling a forbidden implementation, and otherwise
    return the decoded values (numbers, arrays, tensors, or an ``Opaque`` naming another type)."""

    def __init__(self, process: StudentProcess, hint: str = "") -> None:
        self._process = process
        self._path = process.path
        self._hint = hint
        self._time_limit = process.time_limit
        self._blocked: Exception | None = None  # a verdict every later call repeats
        status = process.ready.get("status")
        if status == "forbidden":
            self._blocked = ForbiddenUse(forbidden_message(self._path, process.ready["uses"]))

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)

        def call(*args: Any, **kwargs: Any) -> Any:
            return self._call(name, args, kwargs, gradients=False)[0]

        def with_gradients(*args: Any, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
            """(value, {parameter name: gradient or None}): the student's loss backpropagated in
            their process, through the first torch module among the arguments."""
            return self._call(name, args, kwargs, gradients=True)

        call.with_gradients = with_gradients  # type: ignore[attr-defined]
        call.__name__ = name
        return call

    def _call(self, name: str, args: tuple, kwargs: dict, gradients: bool) -> tuple[Any, dict[str, Any]]:
        if self._blocked is not None:
            raise type(self._blocked)(str(self._blocked))
        reply = self._process.call(name, args, kwargs, gradients)
        status = reply.get("status")
        if status == "ok":
            RECEIVED.append(name)
            grads = {str(key): decode(value) for key, value in dict(reply.get("gradients") or {}).items()}
            return decode(reply.get("value")), grads
        if status == "forbidden":
            self._blocked = ForbiddenUse(forbidden_message(self._path, list(reply.get("uses", []))))
            raise self._blocked
        if status in ("too_slow", "killed_too_slow"):
            self._process.stop()
            self._blocked = TooSlow(
                f"`{name}` did not return within {self._time_limit:g} s (an endless loop?); "
                f"the exercise's later calls are not run{self._hint}"
            )
            raise self._blocked
        if status == "not_written":
            raise NotWritten(f"`{name}` in {self._path} is not written yet (it raises NotImplementedError)")
        if status == "no_function":
            fail(f"{self._path} has no function `{name}`: keep the name and signature of the stub")
        if status == "error":
            fail(f"`{name}` raised {reply.get('type')}: {reply.get('message')}{reply.get('where', '')}")
        if status == "import_error":
            raise ImportFailed(str(reply.get("message")))
        if status == "ended":
            fail(
                f"`{name}` ended its process (exit code {reply.get('code')}): a crash, os._exit or a signal; "
                "the next call starts your module again"
            )
        fail(f"`{name}`: the grader could not read your process's answer ({status})")
        raise AssertionError  # unreachable: fail raises


def call_time_limit(grader: ModuleType | None) -> float:
    if os.environ.get(CALL_LIMIT_ENV):
        return float(os.environ[CALL_LIMIT_ENV])
    return float(getattr(grader, "CALL_TIME_LIMIT_S", DEFAULT_CALL_TIME_LIMIT_S))


def load_submission(
    module_name: str,
    forbidden_names: tuple[str, ...] = (),
    time_limit: float = DEFAULT_CALL_TIME_LIMIT_S,
    hint: str = "",
    preload: tuple[str, ...] = (),
) -> StudentModule:
    """Start the student's process for ``<folder>/<module_name>.py`` (imported there under the guard,
    its source read for forbidden names), once per session: a file that does not import fails every
    test with the same verdict without starting it again."""
    outcome = _started(module_name, forbidden_names, time_limit, hint, preload)
    if isinstance(outcome, BaseException):
        raise type(outcome)(str(outcome))
    return outcome


@functools.cache
def _started(
    module_name: str, forbidden_names: tuple[str, ...], time_limit: float, hint: str, preload: tuple[str, ...]
) -> StudentModule | MissingFile | ImportFailed | TooSlow:
    folder = submission_folder()
    path = folder / f"{module_name}.py"
    if not path.is_file():
        return MissingFile(f"no file {module_name}.py in the submission folder {folder} (set ${SUBMISSION_ENV})")
    process = StudentProcess(path.resolve(), forbidden_names, preload, time_limit)
    PROCESSES.append(process)
    status = process.start()
    if status.get("status") == "import_error":
        return ImportFailed(str(status["message"]))
    if status.get("status") in ("too_slow", "killed_too_slow"):
        return TooSlow(str(status.get("message") or f"importing {path.name} did not finish in time"))
    if status.get("status") == "ended":
        return ImportFailed(f"importing {path.name} ended its process (exit code {status.get('code')})")
    return StudentModule(process, hint)


@pytest.fixture
def submission(request) -> Callable[[str], StudentModule]:
    """``submission("ex01_velocity_keypoints")`` -> the student's module (one process per session),
    guarded by the calling grader's ``FORBIDDEN`` list."""
    forbidden = tuple(getattr(request.module, "FORBIDDEN", ()))
    limit = call_time_limit(request.module)
    hint = getattr(request.module, "TOO_SLOW_HINT", "")
    preload = tuple(getattr(request.module, "STUDENT_IMPORTS", ()))

    def load(module_name: str) -> StudentModule:
        try:
            return load_submission(module_name, forbidden, limit, hint, preload)
        except (MissingFile, ImportFailed, TooSlow) as verdict:
            raise type(verdict)(str(verdict)) from None

    return load


@pytest.hookimpl(hookwrapper=True)
def pytest_pyfunc_call(pyfuncitem: pytest.Function):
    """A grader that fails on an odd value of the student's (an exception while checking it, not a
    check that failed) gives one message saying what was expected (the grader's ``RETURNS``)."""
    RECEIVED.clear()
    outcome = yield
    error = outcome.excinfo[1] if outcome.excinfo else None
    if error is None or not RECEIVED or isinstance(error, (pytest.fail.Exception, pytest.skip.Exception)):
        return
    returns = getattr(pyfuncitem.module, "RETURNS", {})
    expected = "; ".join(f"`{name}` returns {returns[name]}" for name in dict.fromkeys(RECEIVED) if name in returns)
    text = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
    outcome.force_exception(
        pytest.fail.Exception(
            f"your value could not be checked ({text}): expected that {expected or 'the stub documents'}",
            pytrace=False,
        )
    )


def pytest_sessionfinish(session: pytest.Session) -> None:
    for process in PROCESSES:
        process.stop()


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
