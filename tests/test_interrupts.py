"""toolimit.interrupts: the first SIGINT/SIGTERM raises Interrupted, later ones wait for the cleanup,
and the previous handlers come back after a library call."""

from __future__ import annotations

import os
import signal
import time

import pytest

from toolimit.interrupts import Interrupted, interruptible, starting_processes


def _deliver(signum: int) -> None:
    os.kill(os.getpid(), signum)
    time.sleep(0.05)  # the handler runs in the main thread at the next bytecode


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_first_signal_raises_later_ones_wait_and_handlers_come_back(signum):
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    cleaned = False
    with pytest.raises(Interrupted) as stop, interruptible():
        try:
            _deliver(signum)
        finally:
            _deliver(signum)  # a second signal during the cleanup does not interrupt it
            cleaned = True
    assert cleaned and stop.value.signum == signum and stop.value.exit_code == 128 + signum
    assert isinstance(stop.value, KeyboardInterrupt)
    assert {s: signal.getsignal(s) for s in before} == before


def test_a_signal_while_starting_processes_is_held_until_they_are_started():
    steps = []
    with pytest.raises(Interrupted), interruptible():
        with starting_processes():
            _deliver(signal.SIGTERM)
            steps.append("started")
        steps.append("after")
    assert steps == ["started"]
