"""The ``toolimit`` command: one sub-command module per pipeline stage.

Each module in ``COMMANDS`` exposes ``register(subparsers)``, which adds its sub-command and sets
``func`` to a function ``(args) -> int``. User errors raise :class:`CliError` (or a ValueError /
OSError from the library): they print one line and exit with code 2, with no traceback. SIGINT
and SIGTERM stop a command with exit code 130 / 143 and one line, no traceback
(:mod:`toolimit.interrupts`; a command may catch the interruption first to say what it saved).
"""

from __future__ import annotations

import argparse
import importlib
import sys

from toolimit import interrupts

COMMANDS = ("toolimit.cli.demo", "toolimit.cli.align", "toolimit.cli.trajopt", "toolimit.cli.export")


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
    if argv is None:  # the `toolimit` process itself (not a call from Python code): own its signals
        interrupts.install()
    try:
        return int(args.func(args) or 0)
    except interrupts.Interrupted as stop:
        print(f"toolimit {args.command}: interrupted ({stop.signal_name}); nothing more was written", file=sys.stderr)
        return stop.exit_code
    except (CliError, ValueError, OSError, KeyError) as error:
        message = str(error) if not isinstance(error, KeyError) else f"missing key {error}"
        print(f"toolimit {args.command}: error: {message}", file=sys.stderr)
        return 2
    finally:
        if argv is None:
            interrupts.ending()


if __name__ == "__main__":
    sys.exit(main())
