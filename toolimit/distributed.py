"""Work spread over a Ray cluster: the one module that imports Ray (the optional extra ``toolimit[ray]``).

* :func:`ray_cluster` joins the cluster of an address (or of ``RAY_ADDRESS``), or starts a private
  Ray on this machine for the block and stops it after. The private one binds 127.0.0.1 only (its
  node IP is the loopback: Ray's single-machine mode, ``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0``), with
  no dashboard, no metrics export and no usage statistics; its processes start with SIGINT
  blocked, so a Ctrl-C to the terminal's process group is the driver's to handle.
* :func:`ordered_results_on_ray` is :func:`toolimit.workers.ordered_results` on the cluster: one
  actor per cluster CPU runs the initializer once, then tasks; results in index order.
* :class:`FolderTasks` runs functions in a scratch folder on whichever node Ray picks: the driver
  sends the files a task needs and gets back those it wrote, and writes them itself (no shared
  filesystem is assumed). :meth:`FolderTasks.cancel` interrupts the running tasks
  (``ray.cancel``: a KeyboardInterrupt in the task), which send back what they saved so far (a
  learning run's last checkpoint), so the same command resumes from it.

Without Ray installed, :func:`ray_cluster` raises :class:`RayMissing` (one line naming the extra).
"""

from __future__ import annotations

import contextlib
import ipaddress
import logging
import os
import signal
import socket
import tempfile
import threading
import time
from collections.abc import Callable, Generator, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from toolimit.artifacts import atomic_path, inside_folder
from toolimit.errors import InputError
from toolimit.interrupts import SIGNALS, as_interrupted, starting_processes

#: What ``--ray`` / ``ray=`` asks for: False, this machine's worker processes; True, the cluster of
#: ``RAY_ADDRESS`` or else a private Ray on this machine; a string, the address of a cluster to join.
RayTarget = bool | str

Result = TypeVar("Result")

#: How long (s) cancelled tasks get to send back what they saved.
CANCEL_GRACE_S = 30.0
#: Tasks queued per actor ahead of the consumer (as :mod:`toolimit.workers` does per process).
QUEUED_PER_ACTOR = 2
#: How long (s) a cluster's address gets to accept a connection before ``--ray ADDRESS`` gives up:
#: Ray itself retries an address that does not answer for minutes.
CONNECT_TIMEOUT_S = 10.0
#: How long (s) joining a cluster that accepted the connection may take before it is given up.
JOIN_TIMEOUT_S = 30.0
#: The environment of the private Ray's processes: loopback node IP, no usage statistics.
PRIVATE_ENVIRONMENT = {"RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0", "RAY_USAGE_STATS_ENABLED": "0"}


class RayUnreachable(InputError):
    """``--ray ADDRESS`` where no cluster answers."""


class RayMissing(InputError):
    """``--ray`` without Ray installed."""

    def __init__(self) -> None:
        super().__init__('--ray needs Ray: install the extra with pip install "toolimit[ray]"')


def require_ray() -> Any:
    """The ``ray`` module; :class:`RayMissing` where it is not installed."""
    try:
        import ray
    except ImportError:
        raise RayMissing() from None
    return ray


@dataclass(frozen=True)
class Cluster:
    """The Ray cluster this process is connected to: ``private`` when :func:`ray_cluster` started it."""

    address: str
    private: bool

    def nodes(self) -> list[tuple[str, int]]:
        """(name, CPUs) of every alive node (name: :func:`node_name`'s form)."""
        ray = require_ray()
        return [
            (f"{node['NodeManagerAddress']}/{node['NodeID'][:6]}", int(node["Resources"].get("CPU", 0)))
            for node in ray.nodes()
            if node["Alive"]
        ]

    def summary(self) -> str:
        """e.g. ``2 Ray nodes, 4 CPUs`` (for a progress bar)."""
        nodes = self.nodes()
        return f"{len(nodes)} Ray node{'s' * (len(nodes) != 1)}, {sum(c for _, c in nodes)} CPUs"

    def describe(self) -> str:
        """e.g. ``private Ray at 127.0.0.1:6379: 2 Ray nodes, 4 CPUs (127.0.0.1/a1b2c3: 2 CPUs, ...)``."""
        listed = ", ".join(f"{name}: {cpus} CPUs" for name, cpus in self.nodes())
        return f"{'private ' * self.private}Ray at {self.address}: {self.summary()} ({listed})"


def node_name() -> str:
    """The node running this code: its IP and the start of its Ray node id (several nodes may
    share a machine)."""
    ray = require_ray()
    return f"{ray.util.get_node_ip_address()}/{ray.get_runtime_context().get_node_id()[:6]}"


@contextlib.contextmanager
def ray_cluster(target: RayTarget = True, cpus: int | None = None) -> Iterator[Cluster]:
    """Connected to a Ray cluster for the block (see :data:`RayTarget`): an address joins that
    cluster; none (True) joins ``RAY_ADDRESS``'s, else starts a private Ray of ``cpus`` CPUs (default:
    every core) on 127.0.0.1, stopped when the block ends. A process already connected (the caller
    called ``ray.init``) stays connected to its cluster."""
    ray = require_ray()
    if ray.is_initialized():
        yield Cluster(ray.get_runtime_context().gcs_address, private=False)
        return
    address = target if isinstance(target, str) else os.environ.get("RAY_ADDRESS") or None
    if address is not None:
        check_reachable(address)
        # Ray turns a loopback address into this machine's IP unless in its single-machine mode
        on_loopback = loopback_environment() if _is_loopback(address) else contextlib.nullcontext()
        with on_loopback, _keeping_signal_handlers():
            _join_within(address, JOIN_TIMEOUT_S)
        try:
            yield Cluster(address, private=False)
        finally:
            ray.shutdown()
        return
    with loopback_environment(), starting_processes(), _keeping_signal_handlers():
        context = ray.init(
            address="local",
            num_cpus=cpus,
            include_dashboard=False,
            _node_ip_address="127.0.0.1",
            log_to_driver=False,
            configure_logging=False,
        )
    try:
        yield Cluster(context.address_info["address"], private=True)
    finally:
        ray.shutdown()


def _join_within(address: str, timeout_s: float) -> None:
    """``ray.init(address)`` within ``timeout_s`` seconds, else :class:`RayUnreachable`. Ray's
    connection waits in its C++ core, where this process's signal handlers do not run: it is made
    in a daemon thread while the main thread waits, so that SIGINT and SIGTERM still stop the run
    (:mod:`toolimit.interrupts`) and a cluster that accepts connections but never answers as Ray
    gives up in bounded time."""
    ray = require_ray()
    failure: list[BaseException] = []

    def join() -> None:
        try:
            ray.init(address=address, log_to_driver=False, configure_logging=False)
        except BaseException as error:  # handed to the main thread
            failure.append(error)

    # Ray's note that a thread sets no SIGTERM handler is this design's point: errors only while joining
    logger, level = logging.getLogger("ray"), logging.getLogger("ray").level
    logger.setLevel(logging.ERROR)

    thread = threading.Thread(target=join, name="toolimit-ray-join", daemon=True)
    thread.start()
    try:
        thread.join(timeout_s)
    finally:
        logger.setLevel(level)
    if thread.is_alive():
        raise RayUnreachable(
            f"--ray {address}: no Ray cluster answered there within {timeout_s:g} s; check the address"
        )
    if failure:
        error = failure[0]
        raise RayUnreachable(
            f"--ray {address}: cannot join the Ray cluster there ({type(error).__name__}: {error})".splitlines()[0]
        ) from None


def check_reachable(address: str, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
    """:class:`RayUnreachable` (one line) unless the cluster address ``host:port`` (or
    ``ray://host:port``) accepts a connection within ``timeout_s`` seconds: Ray's own
    ``ray.init`` retries for minutes with warnings of its own. Other forms are left to Ray."""
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        return
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s):
            pass
    except OSError as error:
        reason = (
            f"no answer within {timeout_s:g} s" if isinstance(error, TimeoutError) else error.strerror or str(error)
        )
        raise RayUnreachable(
            f"--ray {address}: no Ray cluster answers there ({reason}); "
            "check the address, or start the cluster with `ray start --head`"
        ) from None


def _is_loopback(address: str) -> bool:
    """Whether a cluster address (``host:port``) names this machine's loopback."""
    host = address.rpartition(":")[0].strip("[]") or address
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return host == "localhost"


@contextlib.contextmanager
def loopback_environment() -> Iterator[None]:
    """Within the block, Ray nodes started by this process are private ones: node IP 127.0.0.1
    (so every server binds the loopback only), no usage statistics (:data:`PRIVATE_ENVIRONMENT`,
    inherited by the node's processes). Ray reads its single-machine switch when imported: it is
    set on the imported module too."""
    require_ray()
    import ray._private.ray_constants as constants

    saved = {name: os.environ.get(name) for name in PRIVATE_ENVIRONMENT}
    cluster_mode = constants.ENABLE_RAY_CLUSTER
    os.environ.update(PRIVATE_ENVIRONMENT)
    constants.ENABLE_RAY_CLUSTER = False
    try:
        yield
    finally:
        constants.ENABLE_RAY_CLUSTER = cluster_mode
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


@contextlib.contextmanager
def _signals_as_interrupted() -> Iterator[None]:
    """Around a blocking Ray call: Ray checks for signals while it waits and raises a KeyboardInterrupt
    of its own after this process's handler ran; make it the :class:`Interrupted` the handler meant."""
    try:
        yield
    except KeyboardInterrupt as stop:
        raise as_interrupted(stop) from None


def _get(ref: Any) -> Any:
    """``ray.get(ref)``, a signal meanwhile raising :class:`Interrupted`."""
    with _signals_as_interrupted():
        return require_ray().get(ref)


@contextlib.contextmanager
def _keeping_signal_handlers() -> Iterator[None]:
    """``ray.init`` replaces the SIGTERM handler with one that exits at once: keep this process's
    own (:mod:`toolimit.interrupts`), so SIGTERM stops a run as cleanly as Ctrl-C."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handlers = {signum: signal.getsignal(signum) for signum in SIGNALS}
    try:
        yield
    finally:
        for signum, handler in handlers.items():
            if handler is not None:  # None: a handler not set from Python, nothing to put back
                signal.signal(signum, handler)


class _Runner:
    """An actor holding one worker's state: the initializer runs once, then each task's function."""

    def __init__(self, initializer: Callable[..., None] | None, initargs: tuple[Any, ...]) -> None:
        if initializer is not None:
            initializer(*initargs)

    def run(self, function: Callable[..., Any], args: tuple[Any, ...]) -> Any:
        return function(*args)


def ordered_results_on_ray(
    function: Callable[..., Result],
    arguments: Iterable[tuple[Any, ...]],
    initializer: Callable[..., None] | None = None,
    initargs: tuple[Any, ...] = (),
) -> Generator[Result, None, None]:
    """``function(*arguments[i])`` in index order, on one actor per CPU of the connected cluster
    (each first runs ``initializer(*initargs)``); closing the generator early, or an interrupt,
    cancels the queued tasks and ends the actors."""
    ray = require_ray()
    runner = ray.remote(num_cpus=1)(_Runner)
    shared = ray.put(initargs)  # sent once to the object store, not once per actor
    actors = [runner.remote(initializer, shared) for _ in range(max(1, int(ray.cluster_resources().get("CPU", 1))))]
    pending: list[Any] = []
    try:
        for k, args in enumerate(arguments):
            pending.append(actors[k % len(actors)].run.remote(function, args))
            if len(pending) >= QUEUED_PER_ACTOR * len(actors):
                yield _get(pending.pop(0))
        while pending:
            yield _get(pending.pop(0))
    finally:
        for actor in actors:
            ray.kill(actor)


# --- tasks in scratch folders -----------------------------------------------------------------
#: Files by path relative to a folder, with their bytes.
Files = dict[str, bytes]


def read_files(root: Path, folders: Iterable[str]) -> Files:
    """Every file under ``root / folder`` for each of ``folders`` (missing ones give nothing),
    keyed by its path relative to ``root``. InputError (one line) for a folder or file whose path
    leaves ``root`` (absolute, ``..``, a symbolic link out): nothing outside is read or sent."""
    files: Files = {}
    source, resolved_root = f"files to send from {root}", root.resolve()
    for folder in folders:
        base = inside_folder(root, folder, source)
        paths = [base] if base.is_file() else sorted(p for p in base.rglob("*") if p.is_file())
        for path in paths:
            name = path.relative_to(resolved_root).as_posix()
            files[name] = inside_folder(root, name, source).read_bytes()
    return files


def write_files(root: Path, files: Files) -> None:
    """Write ``files`` under ``root``, each to a temporary name renamed when complete. InputError
    (one line, nothing written) when a name leaves ``root`` (absolute, ``..``, through a symbolic
    link): names come from tasks run elsewhere."""
    targets = {name: inside_folder(root, name, f"a file returned by a task for {root}") for name in files}
    for name, data in files.items():
        with atomic_path(targets[name]) as tmp:
            tmp.write_bytes(data)


@dataclass
class TaskOutcome:
    """What a folder task sent back.

    Attributes:
        value: the function's return value (None when interrupted).
        files: the files it wrote or changed, relative to its folder.
        node: the node that ran it (:func:`node_name`).
        seconds: its wall time on that node.
        folder: the scratch folder it ran in, on that node (gone now): lines it wrote name it.
        interrupted: the task was cancelled; ``files`` hold what it saved until then.
    """

    value: Any
    files: Files
    node: str
    seconds: float
    folder: str
    interrupted: bool = False


def _in_scratch_folder(function: Callable[..., Any], inputs: Files, args: tuple[Any, ...]) -> TaskOutcome:
    """Run on a node: ``function(folder, *args)`` in a fresh folder holding ``inputs``; the files it
    wrote come back, also when it is interrupted (cancelled)."""
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="toolimit-task-") as scratch:
        root = Path(scratch)
        write_files(root, inputs)
        before = {name: (root / name).stat().st_mtime_ns for name in inputs}
        value, interrupted = None, False
        try:
            value = function(root, *args)
        except KeyboardInterrupt:
            interrupted = True
        written = {
            path.relative_to(root).as_posix(): path
            for path in root.rglob("*")
            if path.is_file() and not path.name.startswith(".")
        }
        files = {
            name: path.read_bytes() for name, path in written.items() if before.get(name) != path.stat().st_mtime_ns
        }
    return TaskOutcome(value, files, node_name(), time.perf_counter() - started, scratch, interrupted)


@dataclass
class FolderTasks:
    """Tasks run in scratch folders on the connected cluster (see the module docstring), each
    known by a key; one CPU each unless asked otherwise."""

    _pending: dict[Any, Any] = field(default_factory=dict)

    def submit(self, key: Any, function: Callable[..., Any], inputs: Files, *args: Any, cpus: float = 1) -> None:
        """Start ``function(folder, *args)`` in a folder holding ``inputs``; its outcome comes from
        :meth:`next_done` under ``key``."""
        ray = require_ray()
        remote = ray.remote(num_cpus=cpus, max_retries=3, retry_exceptions=False)(_in_scratch_folder)
        self._pending[key] = remote.remote(function, inputs, args)

    def __len__(self) -> int:
        return len(self._pending)

    def next_done(self) -> tuple[Any, TaskOutcome]:
        """The key and outcome of a task that ended (waiting for one); the task's exception, if it
        raised one (Ray's wrapper of it is also an instance of its class)."""
        ray = require_ray()
        keys = {ref: key for key, ref in self._pending.items()}
        while True:
            with _signals_as_interrupted():
                done, _ = ray.wait(list(keys), num_returns=1, timeout=0.5)
            if done:
                key = keys[done[0]]
                del self._pending[key]
                return key, ray.get(done[0])

    def cancel(self, grace_s: float = CANCEL_GRACE_S) -> list[tuple[Any, TaskOutcome]]:
        """Interrupt every task still running or queued and return the outcomes of those that sent
        back what they saved within ``grace_s`` seconds (a queued task never started: nothing)."""
        ray = require_ray()
        for ref in self._pending.values():
            ray.cancel(ref, force=False)
        outcomes = []
        deadline = time.perf_counter() + grace_s
        for key, ref in self._pending.items():
            with contextlib.suppress(Exception):  # cancelled before it ran, or its node is gone
                outcomes.append((key, ray.get(ref, timeout=max(0.1, deadline - time.perf_counter()))))
        self._pending.clear()
        return outcomes
