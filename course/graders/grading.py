"""Helpers shared by the graders: plain failure messages, number formatting, and the guard that
refuses a submission calling an existing implementation of the function it is asked to write.

Messages: a grader fails with ``fail(...)`` or ``check(condition, ...)``, never a bare ``assert``, so
the student reads one sentence (input, expected, got) without pytest's assertion rewriting; numbers
and arrays go through ``fmt`` (plain decimals, no ``array(..., dtype=float32)``).

Forbidden implementations: each grader lists in ``FORBIDDEN`` the dotted names of the library's
(``toolimit``) and the dependencies' implementations of its exercise; the course's own solutions
and graders are forbidden for every exercise. A name may be a module or package (everything in it),
a class (its methods) or a function. :func:`static_violations` reads the submission's source
(imports, attribute accesses, ``getattr``/``import_module`` with constant strings) and
:class:`Guard` watches every Python call made while the student's code runs (``sys.setprofile``):
a forbidden function that starts, by whatever name or path it was reached (or its source run again,
recognised by its compiled fingerprint), or a thread that starts, ends the exercise with 0 points and
a message saying so. The guard runs in the student's process (``student_process.py``): it is the
honest student's feedback; what protects the score is that process's boundary (``isolation.py``).

Cases: :func:`case_seeds` gives a test its seeds, the public ones or, with the instructor's hidden
seed, cases no student has seen.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import math
import signal
import sys
import threading
import types
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

COURSE = Path(__file__).resolve().parents[1]
GRADERS = COURSE / "graders"
SOLUTIONS = COURSE / "solutions"
#: How a message names the course's own code (solutions, graders): refused by file, never by
#: fingerprint (a student may write a short function as the reference solution does).
COURSE_CODE = ("the course's reference solutions", "the course's graders")
#: The graders' folder's files that run around the student's code (not references of an exercise).
GRADING_MACHINERY = ("conftest.py", "grading.py", "isolation.py", "student_process.py")

#: Modules that start other processes or replace the interpreter's profiler: what runs there is
#: invisible to the guard, and no exercise needs them.
UNWATCHABLE = (
    "subprocess",
    "multiprocessing",
    "concurrent.futures.process",
    "concurrent.futures.ProcessPoolExecutor",
    "os.system",
    "os.popen",
    "os.fork",
    "os.forkpty",
    "os.execv",
    "os.execve",
    "os.execl",
    "os.execle",
    "os.execlp",
    "os.execvp",
    "os.execvpe",
    "os.spawnv",
    "os.spawnve",
    "os.spawnl",
    "os.spawnle",
    "os.posix_spawn",
    "os.posix_spawnp",
    "sys.setprofile",
    "sys.settrace",
    "sys.monitoring",
    "threading.setprofile",
    "threading.settrace",
    "_thread.start_new_thread",
    "_thread.start_new",
    "_thread.start_joinable_thread",
)


# --- cases: public (the student's self-check) or hidden (the instructor's seed) ------------------
#: The instructor's hidden seed (``grade.py --hidden-seed N``); unset, the public cases are graded.
HIDDEN_SEED_ENV = "TOOLIMIT_HIDDEN_SEED"


def case_seeds(count: int, offset: int = 0) -> list[int]:
    """The seeds of ``count`` cases of one test: ``offset .. offset + count - 1`` (public, what the
    student's self-check runs), or, with ``$TOOLIMIT_HIDDEN_SEED`` set, ``count`` seeds drawn from
    it (at least 1000, so never a public one): cases no student has seen."""
    import os

    hidden = os.environ.get(HIDDEN_SEED_ENV)
    if not hidden:
        return list(range(offset, offset + count))
    rng = np.random.default_rng([int(hidden), offset])
    seeds: list[int] = []
    while len(seeds) < count:
        seed = int(rng.integers(1000, 2**31 - 1))
        if seed not in seeds:
            seeds.append(seed)
    return seeds


# --- verdicts: failures that grade.py reads as more than one failed test ------------------------
class Verdict(pytest.fail.Exception):
    """A failure that decides the whole exercise; ``verdict`` is read by grade.py."""

    verdict = "failed"

    def __init__(self, message: str) -> None:
        super().__init__(msg=message, pytrace=False)


class ForbiddenUse(Verdict):
    """The submission calls an existing implementation of the function it is asked to write."""

    verdict = "forbidden"


class NotWritten(Verdict):
    """The function still raises NotImplementedError."""

    verdict = "not_written"


class TooSlow(Verdict):
    """A call did not return within the per-call time limit."""

    verdict = "too_slow"


class ImportFailed(Verdict):
    """The submission file does not import."""

    verdict = "import_error"


class MissingFile(Verdict):
    """No file for this exercise in the submission folder."""

    verdict = "missing"


# --- messages -----------------------------------------------------------------------------------
def fail(message: str) -> None:
    """Fail the test with ``message`` alone (no traceback, no assertion rewriting)."""
    raise pytest.fail.Exception(message, pytrace=False)


def check(condition: Any, message: str | Callable[[], str]) -> None:
    """``fail(message)`` unless ``condition``; ``message`` may be a function (built on failure only)."""
    if not bool(condition):
        fail(message() if callable(message) else message)


def fmt(value: Any, digits: int = 5, limit: int = 10) -> str:
    """Plain text for a number, an array, a tensor or a sequence of them: ``0.12346``,
    ``[1, 2, 3]``, ``[[0.1, 0.2], [0.3, 0.4]]``; more than ``limit`` values per row are elided."""
    if value is None or isinstance(value, (str, bool, np.bool_)):
        return str(value)
    if type(value).__name__ == "Opaque":  # isolation.Opaque: an object of the student's, by its type
        return repr(value)
    if hasattr(value, "detach") and hasattr(value, "cpu"):  # a torch tensor
        value = value.detach().cpu().numpy()
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        number = float(value)
        if math.isnan(number) or math.isinf(number):
            return str(number)
        text = f"{number:.{digits}g}"
        return "0" if text == "-0" else text
    try:
        array = np.asarray(value)
    except Exception:  # noqa: BLE001 - any object: named by its type
        return f"a {type(value).__name__}"
    if array.ndim == 0:
        item = array.item()
        return f"a {type(value).__name__}" if item is value else fmt(item, digits, limit)
    if array.dtype == object:
        return "[" + ", ".join(fmt(item, digits, limit) for item in value) + "]"
    items = list(array)
    if len(items) > limit:
        shown = [fmt(item, digits, limit) for item in items[: limit - 2]] + ["..."]
        shown += [fmt(item, digits, limit) for item in items[-2:]]
        return (
            "[" + ", ".join(shown) + f"] ({len(items)} rows)"
            if array.ndim > 1
            else "[" + ", ".join(shown) + f"] ({len(items)} values)"
        )
    return "[" + ", ".join(fmt(item, digits, limit) for item in items) + "]"


def fmt_shape(value: Any) -> str:
    """``(4, 3)`` for an array-like, ``a float`` for a Python number, the type name otherwise."""
    if isinstance(value, (int, float, np.number)):
        return f"a {type(value).__name__}"
    try:
        return str(tuple(np.shape(value)))
    except Exception:  # noqa: BLE001 - any object the student returned
        return f"a {type(value).__name__}"


# --- the forbidden implementations ---------------------------------------------------------------
def _resolve(name: str) -> Any:
    """The object a dotted name designates (``pkg.module.Class.method``), importing its module."""
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            target = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for attribute in parts[cut:]:
            target = getattr(target, attribute)
        return target
    raise ImportError(f"cannot resolve {name}")


def _module_location(name: str) -> Path | None:
    """The file (module) or folder (package) of a dotted module name, found without importing it
    (importing ``toolimit.learn`` alone takes seconds), or None when the name is not a module."""
    parts = name.split(".")
    try:
        spec = importlib.util.find_spec(parts[0])
    except (ImportError, ValueError):
        return None
    if spec is None or spec.origin is None:
        return None
    if spec.submodule_search_locations is None:
        return Path(spec.origin).resolve() if len(parts) == 1 else None
    location = Path(spec.origin).resolve().parent
    for part in parts[1:]:
        if (location / part).is_dir():
            location = location / part
        elif (location / f"{part}.py").is_file() and part == parts[-1]:
            return location / f"{part}.py"
        else:
            return None
    return location


def _code_objects(target: Any) -> Iterable[types.CodeType]:
    """The code objects of a function (through ``functools.wraps``), a method or a class's methods."""
    if isinstance(target, type):
        for attribute in vars(target).values():
            yield from _code_objects(attribute)
        return
    if isinstance(target, (staticmethod, classmethod)):
        target = target.__func__
    if isinstance(target, property):
        for accessor in (target.fget, target.fset, target.fdel):
            if accessor is not None:
                yield from _code_objects(accessor)
        return
    seen = set()
    while target is not None and id(target) not in seen:
        seen.add(id(target))
        code = getattr(target, "__code__", None)
        if isinstance(code, types.CodeType):
            yield code
        target = getattr(target, "__wrapped__", None)


class Forbidden:
    """What one exercise may not use: modules (by name and file), objects, code objects."""

    def __init__(self, names: Iterable[str], own_file: Path) -> None:
        own = self.own = own_file.resolve()
        self.names: dict[str, str] = {}  # module name or object name -> how the message calls it
        self.files: dict[Path, str] = {}  # a forbidden file or folder -> its description
        self.objects: dict[int, str] = {}
        self.codes: dict[types.CodeType, str] = {}
        self.attributes: dict[str, str] = {}  # method names reached through instances (x.method)
        for name in names:
            location = _module_location(name)
            if location is not None:  # a module or a package: refused by name and by file
                self.names[name] = name
                self.files[location] = name
                continue
            try:
                target = _resolve(name)
            except (ImportError, AttributeError):
                self.names[name] = name  # not installed here: still refused by name
                continue
            self.objects[id(target)] = name
            if isinstance(target, types.ModuleType):
                self.names[target.__name__] = name
                origin = Path(target.__file__).resolve() if getattr(target, "__file__", None) else None
                if origin is not None:
                    self.files[origin.parent if origin.name == "__init__.py" else origin] = name
                continue
            self.names[name] = name
            for code in _code_objects(target):
                self.codes.setdefault(code, name)
            qualified = getattr(target, "__qualname__", "")
            if "." in qualified and not isinstance(target, type):  # a method: also refused as x.method
                self.attributes[qualified.rsplit(".", 1)[-1]] = name
        # the course's own reference code, whatever the exercise
        for folder, what in zip((SOLUTIONS, GRADERS), COURSE_CODE):
            if folder.is_dir():
                self.names[f"course.{folder.name}"] = what
                for path in folder.glob("*.py"):
                    path = path.resolve()
                    if path != own and path.name not in GRADING_MACHINERY:
                        self.files[path] = what
                        if folder == GRADERS:  # importable by name while grading (its folder is on sys.path)
                            self.names[path.stem] = what
        for name in ("grading", "conftest", "isolation", "student_process"):  # the grader's own machinery
            self.names[name] = "the course's grading code"
        for name in UNWATCHABLE:
            self.names[name] = f"{name} (code run there is invisible to the grader)"
        self._file_cache: dict[str, str | None] = {}
        self.call_cache: dict[types.CodeType, str | None] = {}  # filled by Guard
        self.fingerprints = self._fingerprints()

    def _fingerprints(self) -> dict[tuple, str]:
        """The fingerprint of every function compiled from a forbidden library file: the same source run
        again (``exec(inspect.getsource(...))``, a copy saved under another name) has the same one."""
        prints: dict[tuple, str] = {}
        for location, what in self.files.items():
            if what in COURSE_CODE:  # a student's own code may read like a short reference solution
                continue
            paths = sorted(location.rglob("*.py")) if location.is_dir() else [location]
            for path in paths:
                try:
                    code = compile(path.read_text(encoding="utf-8"), str(path), "exec")
                except (OSError, SyntaxError, ValueError):
                    continue
                for nested in _nested_codes(code):
                    print_ = fingerprint(nested)
                    if print_ is not None:
                        prints.setdefault(print_, what)
        return prints

    def code_verdict(self, code: types.CodeType) -> str | None:
        """Why running this code object is forbidden (by identity, file or fingerprint), or None."""
        verdict = self.codes.get(code) or self.file_verdict(code.co_filename)
        if verdict is None:
            print_ = fingerprint(code)
            if print_ is not None and print_ in self.fingerprints:
                verdict = f"{self.fingerprints[print_]} (its source run again)"
        return verdict

    def file_verdict(self, filename: str) -> str | None:
        """The forbidden item a code object's file belongs to, or None."""
        if filename not in self._file_cache:
            verdict = None
            if not filename.startswith("<"):
                path = Path(filename).resolve()
                for forbidden, what in self.files.items():
                    if path == forbidden or forbidden in path.parents:
                        verdict = what
                        break
            self._file_cache[filename] = verdict
        return self._file_cache[filename]

    def object_verdict(self, target: Any) -> str | None:
        """Why an object the submission refers to is forbidden, or None."""
        if id(target) in self.objects:
            return self.objects[id(target)]
        if isinstance(target, types.ModuleType):
            return self.name_verdict(target.__name__)
        for code in _code_objects(target) if callable(target) else ():
            if code in self.codes:
                return self.codes[code]
            verdict = self.file_verdict(code.co_filename)
            if verdict:
                return verdict
        module = getattr(target, "__module__", None)
        if isinstance(module, str) and (isinstance(target, type) or callable(target)):
            return self.name_verdict(module)
        return None

    def name_verdict(self, dotted: str) -> str | None:
        """Why a dotted name (or a module it lies in) is forbidden, or None."""
        for name, what in self.names.items():
            if dotted == name or dotted.startswith(name + "."):
                return what
        return None


#: Shorter bytecode is not fingerprinted: a one-line getter of the student's may equal the library's.
MIN_FINGERPRINT_BYTES = 64


def fingerprint(code: types.CodeType) -> tuple | None:
    """What identifies a function's compiled source, whatever file or name it was run from: its
    name, bytecode, names, variables and constants (nested code objects excluded)."""
    if len(code.co_code) < MIN_FINGERPRINT_BYTES:
        return None
    constants = tuple(repr(value) for value in code.co_consts if not isinstance(value, types.CodeType))
    return (code.co_name, code.co_code, code.co_names, code.co_varnames, constants)


def _nested_codes(code: types.CodeType) -> Iterable[types.CodeType]:
    yield code
    for value in code.co_consts:
        if isinstance(value, types.CodeType):
            yield from _nested_codes(value)


#: The builtins that start a thread (``_thread``'s, whatever copy of the module holds them).
THREAD_STARTERS = ("start_new_thread", "start_new", "start_joinable_thread")


# --- static check --------------------------------------------------------------------------------
def _dotted(node: ast.AST, aliases: dict[str, str]) -> str | None:
    """``a.b.c`` for an attribute chain whose base name was imported, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name) and node.id in aliases:
        return ".".join([aliases[node.id], *reversed(parts)])
    return None


def _lookup(dotted: str) -> tuple[bool, Any]:
    """(found, object) for a dotted name, through modules already imported (no new import)."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        module = sys.modules.get(".".join(parts[:cut]))
        if module is None:
            continue
        target: Any = module
        for attribute in parts[cut:]:
            try:
                target = getattr(target, attribute)
            except Exception:  # noqa: BLE001 - a missing or odd attribute is simply not found
                return False, None
        return True, target
    return False, None


def static_violations(source: str, forbidden: Forbidden) -> list[str]:
    """The forbidden names the source refers to: ``'toolimit.align.keypoints.velocity_keypoints
    (line 5)'``, one entry per use. Read after the module has been imported, so its imports are
    in ``sys.modules`` and names resolve to the objects they designate."""
    tree = ast.parse(source)
    aliases: dict[str, str] = {}
    references: list[tuple[str, int]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                aliases[alias.asname or alias.name.split(".")[0]] = (
                    alias.name if alias.asname else alias.name.split(".")[0]
                )
                references.append((alias.name, node.lineno))
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            for alias in node.names:
                aliases[alias.asname or alias.name] = f"{node.module}.{alias.name}"
                references.append((f"{node.module}.{alias.name}", node.lineno))
            references.append((node.module, node.lineno))
    for builtin in ("getattr", "__import__"):
        aliases.setdefault(builtin, f"builtins.{builtin}")
    problems: list[str] = []
    seen: set[tuple[str, int]] = set()
    # a method name the student defines (class Buffer: def compute_returns_and_advantage) is theirs
    own = {node.name for node in ast.walk(tree) if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))}
    method_names = {name: what for name, what in forbidden.attributes.items() if name not in own}
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            dotted = _dotted(node, aliases)
            if dotted:
                references.append((dotted, node.lineno))
            if node.attr in method_names:
                problems.append(f"{method_names[node.attr]} (line {node.lineno}, .{node.attr})")
        elif isinstance(node, ast.Call) and node.args:
            function = _dotted(node.func, aliases) if isinstance(node.func, ast.Attribute) else None
            if isinstance(node.func, ast.Name):
                function = aliases.get(node.func.id, node.func.id)
            strings = [arg.value for arg in node.args if isinstance(arg, ast.Constant) and isinstance(arg.value, str)]
            if function in ("importlib.import_module", "builtins.__import__") and strings:
                references.append((strings[0], node.lineno))
            elif function == "builtins.getattr" and len(node.args) >= 2 and len(strings) >= 1:
                base = (
                    _dotted(node.args[0], aliases)
                    if not isinstance(node.args[0], ast.Name)
                    else aliases.get(node.args[0].id)
                )
                if base:
                    references.append((f"{base}.{strings[0]}", node.lineno))
                if strings[0] in method_names:
                    problems.append(f"{method_names[strings[0]]} (line {node.lineno}, getattr)")
    for dotted, line in references:
        found, target = _lookup(dotted)
        verdict = forbidden.object_verdict(target) if found else None
        verdict = verdict or forbidden.name_verdict(dotted)
        if verdict and (verdict, line) not in seen:
            seen.add((verdict, line))
            problems.append(f"{verdict} (line {line}, {dotted})")
    return list(dict.fromkeys(problems))


# --- runtime guard -------------------------------------------------------------------------------
class _Stop(BaseException):
    """Raised inside the student's code by the guard or the timer (a BaseException, so an
    ``except Exception`` in the student's code does not hide it; a bare ``except`` may, but the
    guard remembers what it saw)."""


class Guard:
    """Within ``with Guard(forbidden):``, starting a forbidden function records it and raises.
    Imports are let through (a forbidden module may be imported by an allowed one; its functions
    are still watched when they run afterwards).

    ``violation`` names the first forbidden function that started; ``tampered`` is True when the
    code inside replaced the profiler (so nothing could be watched after that)."""

    def __init__(self, forbidden: Forbidden) -> None:
        self.forbidden = forbidden
        self.violation: str | None = None
        self.tampered = False
        self._checked = forbidden.call_cache
        self._imports: list[types.FrameType] = []  # module bodies running (imports under way)

    def _profile(self, frame: types.FrameType, event: str, arg: Any) -> None:
        if event == "return":
            if self._imports and frame is self._imports[-1]:
                self._imports.pop()
            return
        if event == "c_call":
            if getattr(arg, "__module__", None) == "_thread" and getattr(arg, "__name__", "") in THREAD_STARTERS:
                if self.violation is None:
                    self.violation = "a thread (code run there is invisible to the grader)"
                raise _Stop(self.violation)
            return
        if event != "call":
            return
        code = frame.f_code
        if code.co_name == "<module>" and self._is_import(frame):
            self._imports.append(frame)  # importing a module is not calling its functions
            return
        if self._imports:
            return
        if code not in self._checked:
            self._checked[code] = self.forbidden.code_verdict(code)
        verdict = self._checked[code]
        if verdict:
            if self.violation is None:
                what = "imported" if code.co_name == "<module>" else f"{code.co_name}() ran"
                self.violation = f"{verdict} ({what} while your code ran)"
            raise _Stop(self.violation)

    def _is_import(self, frame: types.FrameType) -> bool:
        """True when the frame runs the body of a module being imported from its file (not code
        handed to ``exec``, not the submission itself)."""
        origin = getattr(frame.f_globals.get("__spec__"), "origin", None)
        return (
            origin is not None and origin == frame.f_code.co_filename and Path(origin).resolve() != self.forbidden.own
        )

    def __enter__(self) -> Guard:
        self._previous = sys.getprofile()
        self._hook = self._profile  # one bound method, compared by identity on exit
        sys.setprofile(self._hook)
        threading.setprofile(self._hook)
        return self

    def __exit__(self, *exc: object) -> None:
        current = sys.getprofile()
        # CPython removes a profiler that raised: then the violation is recorded already
        self.tampered = self.violation is None and current is not self._hook
        sys.setprofile(self._previous)
        threading.setprofile(None)


class CallTimer:
    """Within ``with CallTimer(seconds):``, interrupt the code after ``seconds`` (SIGALRM, main
    thread, Linux and macOS; elsewhere no limit). ``expired`` tells whether it fired."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.expired = False
        self._active = (
            seconds > 0 and hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()
        )

    def _alarm(self, signum: int, frame: Any) -> None:
        self.expired = True
        raise _Stop(f"no answer within {self.seconds:g} s")

    def __enter__(self) -> CallTimer:
        if self._active:
            self._previous = signal.signal(signal.SIGALRM, self._alarm)
            signal.setitimer(signal.ITIMER_REAL, self.seconds)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._active:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, self._previous)
