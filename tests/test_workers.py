"""Worker processes: results in order, a stop that leaves no thread of the pool behind, and no
worker outliving a parent that died without cleaning up."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import psutil
import pytest

from toolimit.workers import PARENT_CHECK_S, cores_given, ordered_results, usable_cpus


def _slow_square(value: int) -> int:
    time.sleep(0.05)
    return value * value


def test_results_come_in_order_whatever_the_number_of_workers() -> None:
    arguments = [(value,) for value in range(7)]
    assert list(ordered_results(_slow_square, arguments, workers=2)) == [value * value for value in range(7)]
    assert list(ordered_results(_slow_square, arguments, workers=1)) == [value * value for value in range(7)]


def test_a_consumer_that_stops_early_leaves_no_manager_thread_running() -> None:
    """The pool's manager thread has ended when the generator closes: the interpreter's exit hook then
    has no wake-up pipe left to write to while it closes (a CPython 3.11 race, see
    ``toolimit.workers.stop_workers``)."""

    def managers() -> set[threading.Thread]:
        return {thread for thread in threading.enumerate() if "ExecutorManagerThread" in type(thread).__name__}

    before = managers()
    results = ordered_results(_slow_square, [(value,) for value in range(100)], workers=2)
    assert next(results) == 0
    ours = managers() - before
    assert ours, "the pool's manager thread runs while results are consumed"
    results.close()  # the consumer has enough: stop_workers
    assert not [thread for thread in ours if thread.is_alive()]


@pytest.mark.parametrize(("omp", "cores"), [("1", 1), ("100000", None), ("", None), ("two", None), ("0", None)])
def test_the_cores_given_follow_omp_num_threads(monkeypatch: pytest.MonkeyPatch, omp: str, cores: int | None) -> None:
    """Ray sets OMP_NUM_THREADS to a task's CPUs: never more than the usable ones, junk ignored."""
    monkeypatch.setenv("OMP_NUM_THREADS", omp)
    assert cores_given() == (cores or usable_cpus())


def _running(process: psutil.Process) -> bool:
    """Whether ``process`` still runs: not ended, not a zombie, and not another process that was
    given its pid since (a busy machine reuses pids within the generous bounds of these tests)."""
    try:
        return process.is_running() and process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


#: How long (s) a process may take to end before a test calls it stuck: generous, so that a busy
#: machine (other work on every core) does not fail a test that checks *that* it ends.
ENDING_BOUND_S = 60.0


def _command_line(pid: int) -> bytes:
    """Process ``pid``'s command line (Linux /proc), empty once it has ended."""
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads child processes from /proc")
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGKILL])
def test_workers_end_when_their_parent_dies_without_cleaning_up(tmp_path: Path, signum: int) -> None:
    """A script that installed no handler dies at once on SIGTERM, as on SIGKILL: its workers, which
    would wait on the task queue for ever, end. The bound is generous (a busy machine may delay
    them): the test checks that they end; they check their parent every PARENT_CHECK_S s."""
    script = tmp_path / "parent.py"
    script.write_text(
        textwrap.dedent("""
        import time
        from toolimit.workers import PARENT_CHECK_S, cores_given, ordered_results, usable_cpus

        def wait(value):
            time.sleep(60)
            return value

        if __name__ == "__main__":
            for _ in ordered_results(wait, [(value,) for value in range(8)], workers=2):
                pass
    """)
    )
    parent = subprocess.Popen([sys.executable, str(script)], cwd=tmp_path)
    try:
        deadline = time.monotonic() + 60
        workers: list[int] = []
        while time.monotonic() < deadline and len(workers) < 2:
            children = Path(f"/proc/{parent.pid}/task/{parent.pid}/children").read_text().split()
            workers = [int(pid) for pid in children if b"spawn_main" in _command_line(int(pid))]
            time.sleep(0.05)
        assert len(workers) == 2, "the two workers did not start"
        watched = [psutil.Process(pid) for pid in workers]
        time.sleep(3 * PARENT_CHECK_S)  # their watch has started
        os.kill(parent.pid, signum)
        parent.wait(timeout=ENDING_BOUND_S)
        died = time.monotonic()
        while any(_running(worker) for worker in watched) and time.monotonic() - died < ENDING_BOUND_S:
            time.sleep(0.02)
        assert not [w.pid for w in watched if _running(w)], f"a worker outlived its parent by {ENDING_BOUND_S} s"
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()
