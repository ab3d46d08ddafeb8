"""Stage outputs on disk: written safely, read with one-line errors.

Every file goes to a temporary name and is renamed when complete, so a crash or a bad input never
leaves a half-written ``.npz`` / ``.json`` behind. :func:`load_npz` is the one way ``.npz`` files
are read: a file that is not a readable archive is an input error naming it, not a traceback.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
import zipfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from toolimit.errors import InputError


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` if the block succeeds.

    The temporary file keeps the target's suffix (numpy and others look at it) and is removed if
    the block raises.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.stem}.", suffix=target.suffix, dir=target.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_current_umask())  # mkstemp makes 0600 files; give the usual mode
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


def inside_folder(folder: str | os.PathLike[str], name: Any, source: str) -> Path:
    """``folder / name`` for a ``name`` read from a file in ``folder`` or returned by a task
    (``source`` says which, for the message): a relative path without ``..`` that stays inside
    ``folder`` once symbolic links are followed. InputError otherwise: a planted name must neither
    read nor write nor delete anything outside the folder."""
    if not isinstance(name, str) or not name or "\0" in name:
        raise InputError(f"{source}: {name!r} is not a file name")
    relative = Path(name)
    if relative.is_absolute() or ".." in relative.parts:
        raise InputError(f"{source}: {name!r} leaves the folder {folder} (absolute or with ..); refused")
    root = Path(folder).resolve()
    path = root / relative
    if not path.resolve().is_relative_to(root):
        raise InputError(f"{source}: {name!r} leads outside the folder {folder} through a symbolic link; refused")
    return path


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _to_json(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot write {type(value).__name__} to JSON")


def json_text(data: Any) -> str:
    """``data`` as indented JSON text ending in a newline (numpy arrays and scalars become lists and
    numbers, paths strings)."""
    return json.dumps(data, indent=2, default=_to_json) + "\n"


def save_json(path: str | os.PathLike[str], data: Any) -> None:
    """Write ``data`` as indented JSON (see :func:`json_text`)."""
    save_text(path, json_text(data))


def save_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) atomically; returns the path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def save_npz(path: str | os.PathLike[str], **arrays: Any) -> None:
    """Write arrays to an uncompressed ``.npz`` atomically."""
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez(handle, **arrays)


def load_npz(
    path: str | os.PathLike[str],
    error: type[InputError] = InputError,
    what: str | None = None,
    required: Iterable[str] = (),
) -> dict[str, np.ndarray]:
    """Every array of the ``.npz`` file ``path``, read whole (no pickled objects).

    A missing file is FileNotFoundError; a file that is not a readable archive raises ``error``
    naming it, as "<path>: not a <what> (...)" when ``what`` (e.g. "task file") is given, else
    "<path>: cannot read as .npz (...)"; so does one without every ``required`` key ("<path>:
    missing keys [...]"). Callers check the shapes they need.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")

    def unreadable(reason: str) -> InputError:
        return error(f"{path}: not a {what} ({reason})" if what else f"{path}: cannot read as .npz ({reason})")

    if not zipfile.is_zipfile(path):
        raise unreadable("not a zip archive")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {key: data[key] for key in data.files}
    except (zipfile.BadZipFile, OSError, EOFError) as failure:
        raise unreadable(str(failure)) from None
    except ValueError as failure:  # object arrays need pickle, which is refused
        raise unreadable(f"unreadable array: {failure}") from None
    missing = [key for key in required if key not in arrays]
    if missing:
        raise error(f"{path}: missing keys {missing}")
    return arrays
