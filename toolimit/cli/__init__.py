"""The ``toolimit`` command: one sub-command module per pipeline stage.

Each module in ``COMMANDS`` exposes ``register(subparsers)``, which adds its sub-command and sets
``func`` to a function ``(args) -> int``. User errors raise :class:`CliError` (or a ValueError /
OSError from the library): they print one line and exit with code 2, with no traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys

COMMANDS = ("toolimit.cli.demo", "toolimit.cli.align", "toolimit.cli.replay", "toolimit.cli.trajopt",
            "toolimit.cli.export", "toolimit.cli.learn", "toolimit.cli.evaluate", "toolimit.cli.run")


class CliError(Exception):
    """A user error: bad argument, missing or malformed file."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="toolimit",
        description="A robot learns to use a tool from one video demonstration: "
        "demo (i) -> align (ii) -> trajopt (iii) -> export.",
    )
    subparsers = parser.add_subparsers(dest="command", required=True)
    for module_name in COMMANDS:
        importlib.import_module(module_name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (CliError, ValueError, OSError, KeyError) as error:
        message = str(error) if not isinstance(error, KeyError) else f"missing key {error}"
        print(f"toolimit {args.command}: error: {message}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
