"""Flags built from the settings dataclasses: a flag's type, default and help are its field's own.

A :class:`Flag` names a settings field by its dotted path (``"search.samples"``); :func:`add_flags`
adds it to a parser with the field's type, the help from the field's entry in its class's
``Attributes:`` docstring and the default of the settings the command starts from (or of each
world's preset); :func:`apply_flags` returns those settings with the values given on the command
line. A flag left out keeps the settings' value, so a command and a Python caller start from the
same defaults; a value the settings refuse is a one-line error naming the flag.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import re
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

from toolimit.cli import CliError
from toolimit.errors import InvalidSetting
from toolimit.pipeline.settings import get_value, with_values
from toolimit.workers import MAX_DEFAULT_WORKERS

Settings = TypeVar("Settings")

#: Types a field's text turns into without a ``parse`` of its own.
_SCALARS: dict[Any, Callable[[str], Any]] = {int: int, float: float, str: str}


@dataclass(frozen=True)
class Flag:
    """A command-line flag for one settings field.

    Attributes:
        path: the field's dotted path in the settings (``"search.samples"``).
        name: the flag (default: ``--`` and the field's name with dashes; a bool field that is
            True by default gets ``--no-`` before it).
        parse: turns the flag's text into the field's value (default: the field's type).
        choices: the values the flag accepts, for the help and argparse's check.
        show: the default's text in the help.
    """

    path: str
    name: str | None = None
    parse: Callable[[str], Any] | None = None
    choices: tuple[str, ...] | None = None
    show: Callable[[Any], str] = str

    @property
    def field(self) -> str:
        """The field's own name (the last part of the path)."""
        return self.path.rsplit(".", 1)[-1]


def show_workers(workers: int | None) -> str:
    """The help's text of a ``workers`` default (None: one per core)."""
    return f"one per core, up to {MAX_DEFAULT_WORKERS}" if workers is None else str(workers)


def nested(prefix: str, flags: Sequence[Flag]) -> list[Flag]:
    """``flags`` of settings held in the field ``prefix`` of larger settings (same names and help)."""
    return [dataclasses.replace(flag, path=f"{prefix}.{flag.path}") for flag in flags]


def field_help(cls: type, name: str) -> str:
    """The text of field ``name`` in the ``Attributes:`` section of ``cls``'s docstring (Google
    style: ``name: text`` or ``a, b: text``, continued on deeper-indented lines)."""
    section = (inspect.getdoc(cls) or "").partition("Attributes:")[2]
    entries: dict[str, str] = {}
    current: list[str] = []
    for line in section.splitlines():
        entry = re.match(r"^    (\w+(?:, \w+)*): (.*)$", line)
        if entry:
            current = entry.group(1).split(", ")
            for field in current:
                entries[field] = entry.group(2)
        elif line.startswith("        ") and current:
            for field in current:
                entries[field] += " " + line.strip()
        elif line.strip():
            current = []
    return entries.get(name, "")


def add_flags(parser: argparse.ArgumentParser, flags: Sequence[Flag], defaults: Mapping[str, Any]) -> None:
    """Add ``flags`` to ``parser``. ``defaults`` maps a label to the settings the command starts
    from (one entry with label ``""``, or one per world, and one per tool in a world where it has
    its own values, :func:`~toolimit.pipeline.settings.defaults_by_label`); the help shows each
    one's value, a tool's ("3d scythe") only where it differs from its world's ("3d")."""
    example = next(iter(defaults.values()))
    for flag in flags:
        owner = _owner_class(example, flag.path)
        kind = typing.get_type_hints(owner)[flag.field]
        values = {label: get_value(settings, flag.path) for label, settings in defaults.items()}
        if len(set(map(repr, values.values()))) == 1:
            shown = flag.show(next(iter(values.values())))
        else:
            shown = ", ".join(
                f"{flag.show(value)} {label}"
                for label, value in values.items()
                if " " not in label or repr(value) != repr(values.get(label.rsplit(" ", 1)[0]))
            )
        text = _first_sentence(field_help(owner, flag.field))
        if kind is bool:
            default = next(iter(values.values()))
            name = flag.name or ("--no-" if default else "--") + flag.field.replace("_", "-")
            text = f"turn off: {text}" if default else text
            parser.add_argument(name, dest=flag.path, action="store_const", const=not default, default=None, help=text)
            continue
        parse = flag.parse or _SCALARS[_scalar(kind)]
        parser.add_argument(
            flag_name(flag),
            dest=flag.path,
            metavar=None if flag.choices else flag.field.upper(),
            type=parse,
            choices=flag.choices,
            default=None,
            help=f"{text} (default: {shown})",
        )


def apply_flags(settings: Settings, flags: Sequence[Flag], args: argparse.Namespace) -> Settings:
    """``settings`` with the values of the flags given in ``args``; CliError naming the flag of a
    value the settings refuse."""
    given = {flag.path: getattr(args, flag.path) for flag in flags if getattr(args, flag.path) is not None}
    try:
        return with_values(settings, given)
    except InvalidSetting as error:
        named = [flag for flag in flags if flag.path in given and _names(flag, error.field)]
        raise CliError(f"{flag_name(named[0]) if named else error.field}: {error.problem}") from None


def flag_name(flag: Flag) -> str:
    """The flag of a non-bool field as typed on the command line."""
    return flag.name or "--" + flag.field.replace("_", "-")


def _first_sentence(text: str) -> str:
    """The first sentence of a field's text, cross-reference roles (``:data:`x```) as plain names."""
    plain = re.sub(r":\w+:`~?([^`]+)`", r"\1", text).replace("``", "")
    return re.split(r"(?<=[a-z0-9)])\. ", plain, maxsplit=1)[0].rstrip(".")


def _names(flag: Flag, field: str) -> bool:
    """Whether the settings' ``field`` (as an error names it) is this flag's."""
    flag_name = (flag.name or "").lstrip("-").replace("-", "_")
    return field in (flag.field, flag_name)


def _owner_class(settings: Any, path: str) -> type:
    """The dataclass holding the field at ``path`` of ``settings``."""
    owner = settings
    for name in path.split(".")[:-1]:
        owner = getattr(owner, name)
    if not dataclasses.is_dataclass(owner):
        raise TypeError(f"{path}: {type(owner).__name__} is not a settings dataclass")
    return type(owner)


def _scalar(kind: Any) -> Any:
    """``int`` for ``int | None`` and the like; the type itself otherwise."""
    options = [option for option in typing.get_args(kind) if option is not type(None)]
    return options[0] if options else kind
