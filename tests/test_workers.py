"""Worker processes: results in order, and a stop that leaves no thread of the pool behind."""

from __future__ import annotations

import threading
import time

from toolimit.workers import ordered_results


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
