"""The student's process: imports one exercise module of the student under the guard, then answers
the grader's calls until the grader closes the pipe (``isolation.py`` describes the boundary).

Started by ``conftest.py`` as ``python student_process.py SPEC`` where SPEC is JSON:
``{"path": file, "forbidden": [dotted names], "preload": [modules], "time_limit": seconds}``.
Before the student's module is imported, the modules the exercise needs are imported, then the
process forbids itself threads and processes (seccomp, Linux x86-64). The guard (``grading.py``)
still watches the student's code here: it gives the honest feedback "you called the library";
the score depends only on what this process returns.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import os
import pickle
import sys
import traceback
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent


def student_line(error: BaseException, path: Path) -> str:
    """`` (line 12 of ex01.py)``: where the exception passed last in the student's file, or ''."""
    lines = [frame.lineno for frame in traceback.extract_tb(error.__traceback__) if Path(frame.filename) == path]
    return f" (line {lines[-1]} of {path.name})" if lines else ""


def materialised(result: Any) -> Any:
    """The result with lazy parts computed now, under the guard: an iterator becomes a list, an
    object that only converts to an array (``__array__``) becomes the array; tuples and lists
    element by element. Arrays, tensors, numbers and None are returned as they are."""
    import numpy as np

    if isinstance(result, (tuple, list)):
        return type(result)(materialised(item) for item in result)
    if result is None or isinstance(result, (np.ndarray, np.generic, int, float, complex, bool, str, dict)):
        return result
    if type(result).__module__.split(".")[0] == "torch":
        return result
    if hasattr(result, "__next__"):
        return [materialised(item) for item in result]
    if hasattr(result, "__array__"):
        return np.asarray(result)
    return result


def gradients_of(result: Any, args: tuple, kwargs: dict) -> dict:
    """Backpropagate a scalar loss the student returned; the gradient of every parameter of the
    first ``torch.nn.Module`` among the arguments ({name: tensor or None}), or {"": reason}."""
    import torch

    if not isinstance(result, torch.Tensor) or result.numel() != 1 or not result.requires_grad:
        return {}
    module = next((value for value in (*args, *kwargs.values()) if isinstance(value, torch.nn.Module)), None)
    if module is None:
        return {}
    module.zero_grad(set_to_none=True)
    result.backward()
    return {name: parameter.grad for name, parameter in module.named_parameters()}


def main() -> int:
    spec = json.loads(sys.argv[1])
    # the protocol on private descriptors; what the student prints goes to stderr, stdin is empty
    requests, replies = os.dup(0), os.dup(1)
    empty = os.open(os.devnull, os.O_RDONLY)
    os.dup2(empty, 0)
    os.dup2(2, 1)
    sys.path.insert(0, str(HERE))
    from grading import CallTimer, Forbidden, Guard, _Stop, static_violations
    from isolation import dumps, encode, forbid_threads_and_processes, receive, send

    sys.path.remove(str(HERE))
    while str(HERE) in sys.path:  # the script's folder: the graders are not importable from here
        sys.path.remove(str(HERE))
    for name in spec.get("preload", []):
        importlib.import_module(name)
    path = Path(spec["path"])
    time_limit = float(spec["time_limit"])
    forbidden = Forbidden(spec["forbidden"], path)
    forbid_threads_and_processes()

    def reply(**message: Any) -> None:
        send(replies, dumps(message))

    # the student's module, under the guard and the time limit
    module_spec = importlib.util.spec_from_file_location(f"_submission_{path.stem}", path)
    module = importlib.util.module_from_spec(module_spec)
    guard, timer, error = Guard(forbidden), CallTimer(time_limit), None
    try:
        with guard, timer:
            module_spec.loader.exec_module(module)
    except (Exception, _Stop) as raised:
        error = raised
    uses = [guard.violation] if guard.violation else []
    if guard.tampered and not uses:
        uses.append("sys.setprofile (the grader's watch was switched off)")
    if error is not None and not uses:
        if timer.expired:
            reply(status="too_slow", message=f"importing {path.name} did not finish within {time_limit:g} s")
        else:
            reply(status="import_error", message=f"{path} cannot be imported: {type(error).__name__}: {error}")
        return 0
    uses += static_violations(path.read_text(encoding="utf-8"), forbidden)
    blocked = list(dict.fromkeys(uses))
    reply(status="forbidden" if blocked else "ready", uses=blocked)

    while True:
        try:
            request = pickle.loads(receive(requests))
        except Exception:  # noqa: BLE001 - the grader closed the pipe: done
            return 0
        name = request["function"]
        if blocked:
            reply(status="forbidden", uses=blocked)
            continue
        function = getattr(module, name, None)
        if function is None:
            reply(status="no_function")
            continue
        if not callable(function):
            reply(status="ok", value=encode(function))
            continue
        guard, timer, error, result, gradients = Guard(forbidden), CallTimer(time_limit), None, None, {}
        try:
            with guard, timer:
                result = materialised(function(*request["args"], **request["kwargs"]))
                if request.get("gradients"):
                    gradients = gradients_of(result, request["args"], request["kwargs"])
                encoded = encode(result)
                encoded_gradients = {key: encode(value) for key, value in gradients.items()}
        except (Exception, _Stop) as raised:
            error = raised
        if guard.violation or guard.tampered:
            blocked = [guard.violation or "sys.setprofile (the grader's watch was switched off)"]
            reply(status="forbidden", uses=blocked)
        elif timer.expired:
            reply(status="too_slow")
        elif isinstance(error, NotImplementedError):
            reply(status="not_written")
        elif error is not None:
            text = str(error).strip().splitlines()[0] if str(error).strip() else ""
            reply(status="error", type=type(error).__name__, message=text, where=student_line(error, path))
        else:
            reply(status="ok", value=encoded, gradients=encoded_gradients)


if __name__ == "__main__":
    sys.exit(main())
