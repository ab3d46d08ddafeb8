"""The boundary between the grader and the student's code: they run in two processes.

The grader (pytest, holding the cases, the expected values and the checks) starts one *student
process* per exercise (``student_process.py``), sends it the inputs of each call and receives the
outputs. The student's code never runs in the grader's process, so nothing it does at import or
call time (reading the grader's frames, replacing its checks) can change a score except through
the values it returns.

Both directions are framed messages on pipes: 8 bytes of length, then the payload.
- grader -> student: a pickle (the inputs: arrays, a ``ToolDemo``, a policy, a robot model);
  only the student's process unpickles, and what it receives comes from the grader.
- student -> grader: JSON built by :func:`encode` (numbers, strings, lists, tuples, dicts, numpy
  arrays and tensors as raw bytes with their dtype and shape). The grader never unpickles or
  imports anything from the student: :func:`decode` builds plain numbers and arrays (and scipy's
  sparse matrices from their three arrays), and any other
  object arrives as an :class:`Opaque` naming its type, so a grader's message can say what came.

Linux x86-64 only, :func:`forbid_threads_and_processes` installs a seccomp filter in the student's
process: no thread, no process, no ``ptrace`` or ``kill`` after it (code run in another thread or
process would be invisible to the guard, and could touch the grader's process).
"""

from __future__ import annotations

import base64
import ctypes
import errno
import json
import os
import platform
import select
import struct
import sys
import time
from typing import Any

import numpy as np

#: numpy dtype kinds that travel as raw bytes: bool, signed and unsigned integers, floats, complex.
NUMERIC_KINDS = "biufc"
MAX_MESSAGE_BYTES = 256 * 1024 * 1024
MAX_DEPTH = 16
HEADER = struct.Struct("<Q")


class Opaque:
    """An object the student returned that is not a number, a string, an array or a tensor (or a
    container of them): only its type and a short text travel to the grader."""

    def __init__(self, type_name: str, text: str) -> None:
        self.type_name = type_name
        self.text = text

    def __repr__(self) -> str:
        return f"a {self.type_name}"


class ChannelClosed(Exception):
    """The other process closed its end (it ended)."""


# --- framing -----------------------------------------------------------------------------------
def send(fd: int, payload: bytes) -> None:
    data = HEADER.pack(len(payload)) + payload
    view = memoryview(data)
    while view:
        written = os.write(fd, view)
        view = view[written:]


def receive(fd: int, timeout_s: float | None = None) -> bytes:
    """One message from ``fd``; TimeoutError after ``timeout_s`` seconds without it."""
    deadline = None if timeout_s is None else time.monotonic() + timeout_s
    header = _read_exactly(fd, HEADER.size, deadline)
    (length,) = HEADER.unpack(header)
    if length > MAX_MESSAGE_BYTES:
        raise ChannelClosed(f"a message of {length} bytes (more than {MAX_MESSAGE_BYTES})")
    return _read_exactly(fd, length, deadline)


def _read_exactly(fd: int, size: int, deadline: float | None) -> bytes:
    chunks, missing = [], size
    while missing:
        if deadline is not None:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise TimeoutError
        chunk = os.read(fd, min(missing, 1 << 20))
        if not chunk:
            raise ChannelClosed("the other process ended")
        chunks.append(chunk)
        missing -= len(chunk)
    return b"".join(chunks)


# --- student -> grader: values as JSON ---------------------------------------------------------
def _type_name(value: Any) -> str:
    kind = type(value)
    module = kind.__module__
    return kind.__qualname__ if module == "builtins" else f"{module}.{kind.__qualname__}"


def _short_text(value: Any) -> str:
    try:
        return repr(value)[:200]
    except Exception:  # noqa: BLE001 - any object of the student's
        return ""


def _array(tag: str, array: np.ndarray, **extra: Any) -> dict:
    array = np.array(array, order="C", copy=True)  # (ascontiguousarray makes a 0-d array 1-d)
    return {
        "t": tag,
        "dtype": array.dtype.str,
        "shape": list(array.shape),
        "b64": base64.b64encode(array.tobytes()).decode("ascii"),
        **extra,
    }


def encode(value: Any, depth: int = 0) -> Any:
    """A JSON-ready description of a value the student's function returned (run in the student's
    process). Unknown objects become ``{"t": "opaque", ...}``; nothing of the object runs later."""
    if depth > MAX_DEPTH:
        return {"t": "opaque", "type": "nesting deeper than 16 levels", "text": ""}
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int):
        return {"t": "int", "text": str(value)}
    if isinstance(value, float):
        return {"t": "float", "text": repr(value)}
    if isinstance(value, (list, tuple)):
        tag = "list" if isinstance(value, list) else "tuple"
        return {"t": tag, "items": [encode(item, depth + 1) for item in value]}
    if isinstance(value, dict):
        keys = list(value)
        if all(isinstance(key, str) for key in keys):
            return {"t": "dict", "items": [[key, encode(value[key], depth + 1)] for key in keys]}
    if isinstance(value, np.ndarray) and value.dtype.kind in NUMERIC_KINDS:
        return _array("ndarray", value)
    if isinstance(value, np.generic) and np.dtype(type(value)).kind in NUMERIC_KINDS:
        return _array("npscalar", np.asarray(value))
    torch = sys.modules.get("torch")
    if torch is not None and isinstance(value, torch.Tensor):
        array = value.detach().cpu().numpy()
        return _array("tensor", array, requires_grad=bool(value.requires_grad))
    sparse = sys.modules.get("scipy.sparse")
    if sparse is not None and sparse.issparse(value) and value.dtype.kind in NUMERIC_KINDS:
        matrix = value.tocsc()
        return {
            "t": "sparse",
            "shape": list(matrix.shape),
            "data": _array("ndarray", matrix.data),
            "indices": _array("ndarray", matrix.indices),
            "indptr": _array("ndarray", matrix.indptr),
        }
    return {"t": "opaque", "type": _type_name(value), "text": _short_text(value)}


def _decode_array(data: dict) -> np.ndarray:
    dtype = np.dtype(str(data["dtype"]))
    if dtype.kind not in NUMERIC_KINDS or dtype.hasobject:
        raise ValueError(f"dtype {dtype}")
    shape = tuple(int(n) for n in data["shape"])
    raw = base64.b64decode(str(data["b64"]), validate=True)
    return np.frombuffer(raw, dtype=dtype).reshape(shape).copy()


def decode(data: Any) -> Any:
    """The value :func:`encode` described (run in the grader: builds numbers, strings, containers,
    numpy arrays, torch tensors when torch is loaded, and :class:`Opaque` for anything else)."""
    if data is None or isinstance(data, (bool, str)):
        return data
    if not isinstance(data, dict) or "t" not in data:
        return Opaque("value the grader could not read", "")
    tag = data["t"]
    try:
        if tag == "int":
            return int(str(data["text"]))
        if tag == "float":
            return float(str(data["text"]))
        if tag in ("list", "tuple"):
            items = [decode(item) for item in data["items"]]
            return items if tag == "list" else tuple(items)
        if tag == "dict":
            return {str(key): decode(item) for key, item in data["items"]}
        if tag == "ndarray":
            return _decode_array(data)
        if tag == "npscalar":
            return _decode_array(data)[()]
        if tag == "tensor":
            array = _decode_array(data)
            torch = sys.modules.get("torch")
            if torch is None:
                return array
            return torch.from_numpy(array)
        if tag == "sparse":
            from scipy import sparse

            parts = [_decode_array(data[key]) for key in ("data", "indices", "indptr")]
            return sparse.csc_matrix(tuple(parts), shape=tuple(int(n) for n in data["shape"]))
        if tag == "opaque":
            return Opaque(str(data.get("type", "object"))[:200], str(data.get("text", ""))[:200])
    except (KeyError, TypeError, ValueError, IndexError) as error:
        return Opaque(f"value the grader could not read ({error})", "")
    return Opaque("value the grader could not read", "")


def dumps(message: dict) -> bytes:
    return json.dumps(message, allow_nan=True).encode("utf-8")


def loads(payload: bytes) -> dict:
    message = json.loads(payload.decode("utf-8"))
    if not isinstance(message, dict):
        raise ValueError("not a JSON object")
    return message


# --- the student's process: no thread, no process ---------------------------------------------
#: x86-64 system calls refused in the student's process: clone, fork, vfork, execve, kill, ptrace,
#: tkill, tgkill, process_vm_readv, process_vm_writev, execveat, clone3.
_BLOCKED_SYSCALLS_X86_64 = (56, 57, 58, 59, 62, 101, 200, 234, 310, 311, 322, 435)
_AUDIT_ARCH_X86_64 = 0xC000003E
_SECCOMP_RET_ALLOW = 0x7FFF0000
_SECCOMP_RET_ERRNO = 0x00050000
_PR_SET_NO_NEW_PRIVS, _PR_SET_SECCOMP, _SECCOMP_MODE_FILTER, _PR_SET_DUMPABLE = 38, 22, 2, 4


class _SockFilter(ctypes.Structure):
    _fields_ = [("code", ctypes.c_ushort), ("jt", ctypes.c_ubyte), ("jf", ctypes.c_ubyte), ("k", ctypes.c_uint)]


class _SockFprog(ctypes.Structure):
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.POINTER(_SockFilter))]


def forbid_threads_and_processes() -> bool:
    """From now on this process can start no thread and no process, and cannot ptrace or signal
    another one (seccomp, Linux x86-64; the calls fail with EPERM). False where unsupported."""
    if sys.platform != "linux" or platform.machine() != "x86_64":
        return False
    load_word, jump_equal, jump_greater_equal, ret = 0x20, 0x15, 0x35, 0x06
    blocked = _BLOCKED_SYSCALLS_X86_64
    refuse = 5 + len(blocked) + 1  # index of the "refuse" instruction
    program = [
        (load_word, 0, 0, 4),  # the architecture
        (jump_equal, 1, 0, _AUDIT_ARCH_X86_64),
        (ret, 0, 0, _SECCOMP_RET_ERRNO | errno.EPERM),
        (load_word, 0, 0, 0),  # the system call's number
        (jump_greater_equal, refuse - 5, 0, 0x40000000),  # the x32 ABI
    ]
    for index, number in enumerate(blocked):
        program.append((jump_equal, refuse - (5 + index + 1), 0, number))
    program += [(ret, 0, 0, _SECCOMP_RET_ALLOW), (ret, 0, 0, _SECCOMP_RET_ERRNO | errno.EPERM)]
    filters = (_SockFilter * len(program))(*[_SockFilter(*instruction) for instruction in program])
    fprog = _SockFprog(len(program), filters)
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        return False
    return libc.prctl(_PR_SET_SECCOMP, _SECCOMP_MODE_FILTER, ctypes.byref(fprog), 0, 0) == 0


def keep_memory_private() -> None:
    """Make this (the grader's) process non-dumpable: another process of the same user can then
    neither ptrace it nor read its memory or environment through /proc (Linux; elsewhere nothing)."""
    if sys.platform == "linux":
        ctypes.CDLL(None).prctl(_PR_SET_DUMPABLE, 0, 0, 0, 0)
