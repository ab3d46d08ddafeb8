"""Stopping long work cleanly on SIGINT (Ctrl-C) or SIGTERM (what job controllers and ``timeout`` send).

The first of these signals raises :class:`Interrupted` in the main thread, so the work can save its
progress and stop its worker processes; any later one (a second Ctrl-C, the signal sent to the
whole process group) is ignored while that cleanup runs, so it cannot break the cleanup with a
second traceback. :class:`Interrupted` is a KeyboardInterrupt: code that catches Ctrl-C catches it.

* a command-line program calls :func:`install` once: the handlers stay for the process's life;
* a library call wraps its work in :func:`interruptible`: the handlers are in place during the
  block and the previous ones come back afterwards (nothing changes outside the main thread, or
  inside an outer :func:`install` or :func:`interruptible`).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType

SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived; ``signum`` says which, ``exit_code`` is the shell's 128 + signum."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum

    @property
    def signal_name(self) -> str:
        return signal.Signals(self.signum).name

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


_state: dict[str, object] = {"interrupted": False, "deferred": False}


def _handler(signum: int, frame: FrameType | None) -> None:
    if _state["interrupted"]:
        return  # cleanup of the first interrupt is running: do not break it
    if _state["deferred"]:
        _state.setdefault("held", signum)  # raised when :func:`starting_processes` ends
        return
    _state["interrupted"] = True
    _state["signum"] = signum
    raise Interrupted(signum)


def as_interrupted(stop: KeyboardInterrupt) -> Interrupted:
    """``stop`` as an :class:`Interrupted`: a library that checks for signals inside its own calls
    (Ray) raises a plain KeyboardInterrupt of its own after the handler ran; this names the signal
    the handler saw (SIGINT when none did: a KeyboardInterrupt raised otherwise)."""
    if isinstance(stop, Interrupted):
        return stop
    signum = _state.get("signum", signal.SIGINT)
    return Interrupted(signum if isinstance(signum, int) else signal.SIGINT)


def install() -> None:
    """Route SIGINT and SIGTERM to :class:`Interrupted` for the rest of the process (main thread only)."""
    for signum in SIGNALS:
        signal.signal(signum, _handler)


@contextlib.contextmanager
def interruptible() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM raise :class:`Interrupted` once (see the module docstring)."""
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) is _handler:
        yield
        return
    previous = {signum: signal.getsignal(signum) for signum in SIGNALS}
    install()
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        _state["interrupted"] = False


@contextlib.contextmanager
def starting_processes() -> Iterator[None]:
    """Around code that starts child processes: no signal may cut it halfway, none gets lost.

    SIGINT is blocked in the calling thread (POSIX), and children started here inherit that mask: a
    Ctrl-C sent to the process group never reaches them, even while Python starts up; their parent
    decides when they stop. An interrupt arriving meanwhile is held and raised when the block ends,
    so a child is never left reading a half-written start-up message.
    """
    blocking = hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread()
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT}) if blocking else None
    _state["deferred"] = True
    try:
        yield
    finally:
        _state["deferred"] = False
        if previous is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)  # a pending SIGINT is handled here
        held = _state.pop("held", None)
        if isinstance(held, int) and not _state["interrupted"]:
            _state["interrupted"] = True
            raise Interrupted(held)


def ending() -> None:
    """Ignore SIGINT and SIGTERM from now on: the process is ending, let no late signal turn its
    exit code into a kill (Python keeps ignored signals ignored during its shutdown)."""
    if threading.current_thread() is threading.main_thread():
        for signum in SIGNALS:
            signal.signal(signum, signal.SIG_IGN)
