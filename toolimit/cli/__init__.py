"""The ``toolimit`` command: one sub-command module per pipeline stage.

Each module in ``COMMANDS`` exposes ``register(subparsers)``, which adds its sub-command and sets
``func`` to a function ``(args) -> int``. User errors (a :class:`toolimit.errors.ToolimitError`, such as
:class:`CliError`, or an OSError for a missing or unreadable file) print one line and exit with
code 2; anything else is a bug in the package and shows its traceback. SIGINT
and SIGTERM stop a command with exit code 130 / 143 and one line, no traceback
(:mod:`toolimit.interrupts`; a command may catch the interruption first to say what it saved).
"""

from __future__ import annotations

import argparse
import importlib
import sys
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

from toolimit import __version__, interrupts
from toolimit.errors import InputError, StageFoundNothing, ToolimitError

if TYPE_CHECKING:
    from toolimit.trajopt import PoseTargets

COMMANDS = (
    "toolimit.cli.demo",
    "toolimit.cli.align",
    "toolimit.cli.replay",
    "toolimit.cli.trajopt",
    "toolimit.cli.export",
    "toolimit.cli.learn",
    "toolimit.cli.evaluate",
    "toolimit.cli.run",
    "toolimit.cli.reproduce",
)


class CliError(InputError):
    """A user error found by the command line: a bad argument, a missing or malformed file."""


class _OneLineErrorParser(argparse.ArgumentParser):
    """argparse, but a usage error (unknown choice, missing option) is one line, exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def check_writable_folder(folder: Path, option: str) -> None:
    """Raise CliError unless files can be created in ``folder`` (created later if missing): checked
    before any work, so that a long run never ends in an unwritable output."""
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise CliError(f"{option}: cannot write in {folder}: {existing} is a file, not a folder")
    try:
        with tempfile.NamedTemporaryFile(dir=existing, prefix=".toolimit-write-check."):
            pass
    except OSError as error:
        raise CliError(
            f"{option}: cannot write in {folder}: creating a file in {existing} fails ({error.strerror})"
        ) from None


def check_output_folder(folder: Path, option: str) -> None:
    """CliError unless ``folder`` is (or can be made) a writable folder; checked before any work."""
    if folder.exists() and not folder.is_dir():
        raise CliError(f"{option}: {folder} exists and is not a folder")
    check_writable_folder(folder, option)


def check_output_file(path: Path | None, option: str, suffix: str) -> None:
    """CliError unless ``path`` (when given) ends in ``suffix`` and its folder is writable."""
    if path is None:
        return
    if path.suffix != suffix:
        raise CliError(f"{option}: expected a {suffix} file name, got {path}")
    check_writable_folder(path.parent, option)


def check_choice(option: str, value: str, choices: Iterable[str], what: str) -> None:
    """CliError unless ``value`` is one of ``choices``: names the option, the ``what`` ("tool for
    world 3d") and the choices."""
    known = list(choices)
    if value not in known:
        raise CliError(f"{option}: unknown {what} {value!r}; choose one of {', '.join(known)}")


def check_scene(tool: str, world: str) -> None:
    """CliError unless a scene exists for ``--tool`` in ``--world`` (the world is checked first)."""
    from toolimit.scenes.registry import WORLDS, available_scenes

    check_choice("--world", world, WORLDS, "world")
    tools = sorted(name for name, scene_world in available_scenes() if scene_world == world)
    if tool not in tools:
        raise CliError(f"--tool: unknown tool {tool!r} for world {world}; choose one of {', '.join(tools)}")


def check_count(option: str, value: int, minimum: int = 1) -> None:
    """CliError unless ``value`` >= ``minimum`` (1: a positive integer, 0: a non-negative one)."""
    if value < minimum:
        kind = "positive" if minimum == 1 else "non-negative" if minimum == 0 else f">= {minimum}"
        raise CliError(f"{option}: must be a {kind} integer, got {value}")


def add_scene_arguments(parser: argparse.ArgumentParser, default_world: str) -> None:
    """``--tool`` and ``--world``: the scene a command works in (checked by :func:`check_scene`)."""
    add_tool_argument(parser)
    add_world_argument(parser, default_world)


def add_tool_argument(parser: argparse.ArgumentParser) -> None:
    """``--tool`` (required): the tool a command works with, one of the registered tools."""
    from toolimit.tools import TOOLS

    parser.add_argument("--tool", required=True, help=", ".join(TOOLS))


def add_world_argument(parser: argparse.ArgumentParser, default: str) -> None:
    """``--world``: the scene's world, ``default`` when not given (checked by :func:`check_scene`)."""
    parser.add_argument("--world", default=default, help=f"planar or 3d (default: {default})")


def add_seed_argument(parser: argparse.ArgumentParser, what: str = "random seed", default: int = 0) -> None:
    """``--seed``: the integer seed of ``what`` (same seed, same result)."""
    parser.add_argument("--seed", type=int, default=default, help=f"{what} (default: {default})")


def add_out_argument(parser: argparse.ArgumentParser, what: str = "output folder") -> None:
    """``--out`` (required): where a command writes, ``what`` for the help."""
    parser.add_argument("--out", required=True, type=Path, help=what)


def add_ray_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """``--ray [ADDRESS]``: ``what`` on a Ray cluster (:data:`toolimit.distributed.RayTarget`)."""
    from toolimit.distributed import CONNECT_TIMEOUT_S, JOIN_TIMEOUT_S

    parser.add_argument(
        "--ray",
        nargs="?",
        const=True,
        default=False,
        metavar="ADDRESS",
        help=f"{what} on a Ray cluster: the one at ADDRESS (e.g. 10.0.0.5:6379), else RAY_ADDRESS's, else a "
        'private Ray on this machine, on 127.0.0.1 only, for this run (needs pip install "toolimit[ray]"). '
        "A cluster on a network runs code for anyone who reaches it: start it with token authentication "
        "(RAY_AUTH_MODE=token on every node and here, the token from `ray get-auth-token --generate` in "
        "~/.ray/auth_token or RAY_AUTH_TOKEN) on a network you trust. An ADDRESS that does not answer is given up "
        f"after {CONNECT_TIMEOUT_S + JOIN_TIMEOUT_S:g} s at most",
    )


def check_ray(target: bool | str) -> None:
    """CliError-like one line (exit 2) for ``--ray`` without Ray installed; checked before any work."""
    if target:
        from toolimit.distributed import require_ray

        require_ray()


def add_frame_argument(parser: argparse.ArgumentParser) -> None:
    """``--frame``: the orientation convention of a poses file (see :func:`load_poses`)."""
    parser.add_argument(
        "--frame",
        choices=("tool", "original-spade"),
        default="tool",
        help="orientation convention of the poses: toolimit's tool frame (default), or the original code's "
        "spade tip frame of the shared real recordings (converted to the tool frame)",
    )


def load_poses(path: Path, frame: str) -> PoseTargets:
    """The target poses of the file ``path`` in toolimit's tool frame (converted from the original
    code's spade tip frame when ``frame`` is "original-spade")."""
    from toolimit.trajopt import from_original_spade_tip, load_pose_targets

    targets = load_pose_targets(path)
    return from_original_spade_tip(targets) if frame == "original-spade" else targets


def build_parser() -> argparse.ArgumentParser:
    parser = _OneLineErrorParser(
        prog="toolimit",
        description="A robot learns to use a tool from one video demonstration: "
        "demo (i) -> align (ii) -> trajopt (iii) -> learn (iv) -> export; `run` does them all.",
    )
    parser.add_argument("--version", action="version", version=f"toolimit {__version__}")
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
        print(f"toolimit {args.command}: interrupted ({stop.signal_name})", file=sys.stderr)
        return stop.exit_code
    except StageFoundNothing as nothing:
        print(f"toolimit {args.command}: {nothing}", file=sys.stderr)
        return 1
    except (ToolimitError, OSError) as error:
        print(f"toolimit {args.command}: error: {error}", file=sys.stderr)
        return 2
    except MemoryError:  # the sizes asked for (frames, rates, budgets) need more memory than there is
        print(
            f"toolimit {args.command}: error: out of memory: the values given ask for more than this machine holds",
            file=sys.stderr,
        )
        return 2
    except OverflowError as error:  # a value given too large for the arithmetic it enters
        print(f"toolimit {args.command}: error: a value given is too large ({error})", file=sys.stderr)
        return 2
    finally:
        if argv is None:
            interrupts.ending()


if __name__ == "__main__":
    sys.exit(main())
