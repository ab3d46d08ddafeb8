"""Name lists that follow a registry: read-only sequences recomputed at every use, so a module-level
constant such as ``ROBOTS`` never goes stale when a name is registered after it was imported."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import overload


class LiveNames(Sequence[str]):
    """The names ``names()`` returns now, as a read-only sequence (``in``, iteration, indexing,
    ``", ".join``); ``label`` is shown by ``repr``."""

    def __init__(self, label: str, names: Callable[[], Sequence[str]]) -> None:
        self._label = label
        self._names = names

    @overload
    def __getitem__(self, index: int) -> str: ...

    @overload
    def __getitem__(self, index: slice) -> Sequence[str]: ...

    def __getitem__(self, index: int | slice) -> str | Sequence[str]:
        return tuple(self._names())[index]

    def __len__(self) -> int:
        return len(self._names())

    def __repr__(self) -> str:
        return f"{self._label}{tuple(self)!r}"
