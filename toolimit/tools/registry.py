"""The tool registry: one :class:`ToolRecord` per tool name, read by every stage.

``register_tool(record)`` adds a tool (the built-in ones register in their own modules,
:mod:`toolimit.tools.spade` and its siblings); scenes (:func:`toolimit.scenes.make_scene`), scripted
motions, synthetic demonstrations, robots (the tool's length), alignment (the planar plane) and the
Gymnasium ids all look the tool up here, so no stage branches on a tool's name.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping
from typing import Any

from toolimit.errors import InputError
from toolimit.tools.record import ToolRecord, ToolSpec, check_entry_point

_RECORDS: dict[str, ToolRecord] = {}


def register_tool(record: ToolRecord, overwrite: bool = False) -> None:
    """Add ``record`` under ``record.name``; InputError if that name is taken, unless ``overwrite``
    (then the record replaces the registered one: a researcher's own scene of a known tool)."""
    if not isinstance(record, ToolRecord):
        raise InputError(f"register_tool takes a ToolRecord, got {type(record).__name__}")
    if record.name in _RECORDS and not overwrite:
        raise InputError(f"tool {record.name!r} is already registered (overwrite=True replaces it)")
    _RECORDS[record.name] = record


def find_tool(name: str) -> ToolRecord | None:
    """The record of the tool called ``name``, None if no tool has that name."""
    return _RECORDS.get(name)


def tool_record(name: str) -> ToolRecord:
    """The record of the tool called ``name``; InputError listing the known tools otherwise."""
    record = find_tool(name)
    if record is None:
        raise InputError(f"unknown tool {name!r}; known tools: {', '.join(sorted(_RECORDS))}")
    return record


def tool_records() -> tuple[ToolRecord, ...]:
    """Every registered record, in registration order."""
    return tuple(_RECORDS.values())


def tool_spec(name: str) -> ToolSpec:
    """The dimensions of the tool called ``name``; a clear error for an unknown one."""
    return tool_record(name).spec


class _ToolSpecs(Mapping[str, ToolSpec]):
    """Tool name -> :class:`ToolSpec` of every registered tool, read from the registry at each use."""

    def __getitem__(self, name: str) -> ToolSpec:
        return _RECORDS[name].spec

    def __iter__(self) -> Iterator[str]:
        return iter(tuple(_RECORDS))

    def __len__(self) -> int:
        return len(_RECORDS)

    def __repr__(self) -> str:
        return f"TOOLS({dict(self)!r})"


#: Tool name -> ToolSpec of every registered tool (a live read-only view of the registry).
TOOLS: Mapping[str, ToolSpec] = _ToolSpecs()


def load_entry_point(entry_point: str) -> Any:
    """The object named by ``"module:name"``, its module imported only now."""
    check_entry_point(entry_point, "entry point")
    module_name, name = entry_point.split(":")
    return getattr(importlib.import_module(module_name), name)
