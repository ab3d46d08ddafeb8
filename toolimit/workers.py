"""Work spread over spawned worker processes, results in order, stopped at once by Ctrl-C.

``ordered_results(function, arguments, workers, initializer, initargs)`` yields
``function(*arguments[i])`` in index order, computing them in ``workers`` processes started with the
"spawn" method (each first runs ``initializer(*initargs)``, e.g. to build its scene once). At most
two tasks per worker are queued ahead of the consumer, so a consumer that stops early (the
alignment, once it holds enough candidates) wastes little. Workers ignore SIGINT: a Ctrl-C to the
process group is the parent's to handle (:mod:`toolimit.interrupts`); when the consumer stops early
or is interrupted, queued tasks are cancelled and the processes end without waiting for running ones.
Results do not depend on the number of workers as long as each task draws its randomness from its
own arguments. A script that uses workers needs the ``if __name__ == "__main__":`` guard.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Generator, Iterable
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any, TypeVar

from toolimit.distributed import ordered_results_on_ray
from toolimit.interrupts import starting_processes

Result = TypeVar("Result")
#: Longest wait (s) for a stopped executor's manager thread to finish (:func:`stop_workers`).
MANAGER_JOIN_S = 5.0
#: How often (s) a worker checks that the process that started it still runs (:func:`_exit_with_parent`).
PARENT_CHECK_S = 0.1


#: Most worker processes used by default, however many cores the machine has.
MAX_DEFAULT_WORKERS = 4


def worker_count(requested: int | None) -> int:
    """``requested`` workers, or one per CPU core up to :data:`MAX_DEFAULT_WORKERS` when None."""
    return requested if requested is not None else min(MAX_DEFAULT_WORKERS, usable_cpus())


def usable_cpus() -> int:
    """The CPU cores this process may run on (its affinity where the system has one), at least 1."""
    affinity = getattr(os, "sched_getaffinity", None)
    return max(1, len(affinity(0)) if affinity is not None else os.cpu_count() or 1)


def cores_given() -> int:
    """The cores this process's threads should use: :func:`usable_cpus`, or fewer where
    ``OMP_NUM_THREADS`` says so (Ray sets it to a task's CPUs, job schedulers to a job's)."""
    given = os.environ.get("OMP_NUM_THREADS", "")
    return max(1, min(usable_cpus(), int(given))) if given.isdigit() and int(given) > 0 else usable_cpus()


def ordered_results(
    function: Callable[..., Result],
    arguments: Iterable[tuple[Any, ...]],
    workers: int,
    initializer: Callable[..., None] | None = None,
    initargs: tuple[Any, ...] = (),
    on_ray: bool = False,
) -> Generator[Result, None, None]:
    """``function(*args)`` for each ``args`` of ``arguments``, in order (module docstring); in
    this process when ``workers`` is 1 (``initializer`` is then not called); ``on_ray``: on the
    Ray cluster this process is connected to instead, one actor per CPU (``workers`` unused)."""
    if on_ray:
        yield from ordered_results_on_ray(function, arguments, initializer, initargs)
        return
    if workers == 1:
        for args in arguments:
            yield function(*args)
        return
    context = multiprocessing.get_context("spawn")
    executor = ProcessPoolExecutor(
        workers, mp_context=context, initializer=_start_worker, initargs=(os.getpid(), initializer, initargs)
    )
    pending: list[Future[Result]] = []
    finished = False
    try:
        for args in arguments:
            if len(pending) < workers:  # the submits that start the worker processes
                with starting_processes():
                    pending.append(executor.submit(function, *args))
            else:
                pending.append(executor.submit(function, *args))
            if len(pending) >= 2 * workers:
                yield pending.pop(0).result()
        while pending:
            yield pending.pop(0).result()
        finished = True
    finally:
        if finished:  # every task done: the idle workers exit on their own, cleanly
            executor.shutdown(wait=True)
        else:
            stop_workers(executor)


def _start_worker(parent: int, initializer: Callable[..., None] | None, initargs: tuple[Any, ...]) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C to the process group is the parent's to handle
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # ignored now: no need to keep it blocked
    _exit_with_parent(parent)
    if initializer is not None:
        initializer(*initargs)


def _exit_with_parent(parent: int) -> None:
    """End this worker within :data:`PARENT_CHECK_S` of the death of its parent (process id
    ``parent``, given by the parent itself), however the parent died.

    A parent that cannot clean up (SIGTERM to a script that installed no handler, SIGKILL, a crash)
    would otherwise leave its workers waiting on the task queue for ever: they hold its write end
    themselves, so it never reports the end of the input. A daemon thread watches the parent id,
    which changes when the process is re-parented. The id is the one the parent gave, not this
    process's parent at the time the watch starts: on a busy machine a worker may still be starting
    (importing) when its parent dies, and would then watch its new parent.
    """

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_CHECK_S)
        os._exit(1)  # the results have no reader any more: nothing to flush or save

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


def stop_workers(executor: ProcessPoolExecutor) -> None:
    """Cancel the queued tasks and end the worker processes now, without waiting for running ones
    (their results are not needed: the consumer has enough, or was interrupted). Python 3.14 has
    ``executor.terminate_workers()``; before it, the processes are only reachable as ``_processes``."""
    processes = list((getattr(executor, "_processes", None) or {}).values())
    # The executor's manager thread sees its workers end and closes its wake-up pipe. Wait for it:
    # on CPython 3.11 the interpreter's exit hook may otherwise write to that pipe while it closes
    # ("OSError: Bad file descriptor" printed at exit, seen in this project's test runs). Read it
    # before ``shutdown``, which forgets it.
    manager = getattr(executor, "_executor_manager_thread", None)
    executor.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    if manager is not None:
        manager.join(timeout=MANAGER_JOIN_S)
    for process in processes:
        process.join(timeout=1.0)
