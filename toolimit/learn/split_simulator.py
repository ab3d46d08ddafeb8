"""B instances of a task stepped by several processes at once: a second core for the physics.

:class:`SplitSimulator` has the interface of :class:`~toolimit.learn.simulator.TaskSimulator` that
the batched VecEnv uses. Its batch is cut into consecutive parts (:class:`BatchPart`); the first is
simulated in this process, each other one in a spawned worker process holding its own
TaskSimulator. A step writes the workers' actions into a buffer they share with this process (a
file in ``/dev/shm`` mapped by both and unlinked as soon as both hold it, so nothing outlives them),
wakes them with one byte each on a pipe, simulates the first part meanwhile, and waits for one
byte back; the workers write observations, rewards, goal rewards, joints and success into the same
buffer. Nothing is pickled per step; a reset sends the batch generator's state (and the ADR bounds
or the given box positions) pickled, once per episode.

Results do not depend on the number of processes: every part draws its reset randomness for the
whole batch from a copy of the generator and keeps its share (:mod:`toolimit.learn.batch_part`),
and the physics of an instance does not depend on the other instances of its batch. The scenes
that draw instance by instance (the planar ones) cannot be split: ValueError at the first reset.

Stopping: workers ignore SIGINT (a Ctrl-C to the process group is the main process's to handle,
:mod:`toolimit.interrupts`) and leave on :meth:`SplitSimulator.close`, on the end of their pipe (the
main process is gone) or on SIGTERM (multiprocessing's exit hook terminates them: they are daemons).
"""

from __future__ import annotations

import contextlib
import mmap
import multiprocessing
import os
import pickle
import signal
import tempfile
import traceback
from multiprocessing.connection import Connection
from typing import Any

import numpy as np

from toolimit.interrupts import starting_processes
from toolimit.learn.batch_part import BatchPart
from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.task import LearningTask

#: Messages on the pipes (bytes, never pickled per step).
_STEP, _RESET, _QUIT, _DONE, _FAILED = b"s", b"r", b"q", b"d", b"e"
#: Longest wait (s) for a worker to leave after the quit message, then after SIGTERM.
QUIT_WAIT_S, TERMINATE_WAIT_S = 0.3, 0.2
#: Where the shared buffers live (memory-backed on Linux).
SHARED_DIR = "/dev/shm" if os.path.isdir("/dev/shm") else tempfile.gettempdir()


class SharedBuffers:
    """A part's per-step arrays, in one float64 matrix mapped from a file both processes open.

    Columns: actions (N), observation (D; float32 values, exact in float64), reward, goal
    reward, joints q (N, rad), success (0 or 1)."""

    def __init__(self, path: str, size: int, n_joints: int, observation_size: int, create: bool):
        columns = 2 * n_joints + observation_size + 3
        nbytes = size * columns * 8
        flags = os.O_RDWR | (os.O_CREAT | os.O_EXCL if create else 0)
        descriptor = os.open(path, flags, 0o600)
        try:
            if create:
                os.ftruncate(descriptor, nbytes)
            self._map = mmap.mmap(descriptor, nbytes)
        finally:
            os.close(descriptor)
        matrix = np.ndarray((size, columns), dtype=np.float64, buffer=self._map)
        n, d = n_joints, observation_size
        self.actions, self.observations = matrix[:, :n], matrix[:, n : n + d]
        self.rewards, self.goals = matrix[:, n + d], matrix[:, n + d + 1]
        self.q, self.success = matrix[:, n + d + 2 : 2 * n + d + 2], matrix[:, 2 * n + d + 2]

    def write(self, simulator: TaskSimulator, observations: np.ndarray, rewards: np.ndarray, goals: np.ndarray) -> None:
        """The results of a reset or step of ``simulator``."""
        self.observations[:], self.rewards[:], self.goals[:] = observations, rewards, goals
        self.q[:], self.success[:] = simulator.q, simulator.is_success() if simulator.t else False

    def close(self) -> None:
        del self.actions, self.observations, self.rewards, self.goals, self.q, self.success
        self._map.close()


def _serve(connection: Connection, task: LearningTask, part: BatchPart, options: dict[str, Any], path: str) -> None:
    """A worker: its part's TaskSimulator, answering steps and resets until told to quit or the pipe ends."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C to the process group is the parent's to handle
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # ignored now: no need to keep it blocked
    simulator = TaskSimulator(task, part=part, **options)
    buffers = SharedBuffers(path, part.size, simulator.n_joints, simulator.observation_size, create=False)
    connection.send_bytes(_DONE)
    while True:
        try:
            message = connection.recv_bytes()
        except (EOFError, OSError):
            break  # the main process is gone
        if message == _QUIT:
            break
        try:
            if message == _STEP:
                buffers.write(simulator, *simulator.step(buffers.actions))
            else:  # a reset: the batch generator's state, the box positions, the ADR bounds
                state, box_positions, bounds = pickle.loads(message[1:])
                rng = np.random.default_rng()
                rng.bit_generator.state = state
                simulator.adr_bounds = bounds
                buffers.write(simulator, simulator.reset(rng, box_positions), np.zeros(part.size), np.zeros(part.size))
            answer = _DONE
        except Exception:  # the main process raises it, with this traceback
            answer = _FAILED + traceback.format_exc().encode()
        try:
            connection.send_bytes(answer)
        except OSError:
            break  # the main process is gone
    buffers.close()
    os._exit(0)  # at once: the interpreter's teardown (numba, pinocchio) would outlast the main process


class SplitSimulator:
    """B instances of ``task`` in ``processes`` processes (see the module docstring); the
    TaskSimulator arguments are its own. Call :meth:`close` (the VecEnv's ``close``) to end the
    workers."""

    def __init__(
        self,
        task: LearningTask,
        batch_size: int,
        processes: int,
        scene_kwargs: dict[str, Any] | None = None,
        reward: str = "sparse",
        adr: bool = False,
    ):
        if not 2 <= processes <= batch_size:
            raise ValueError(f"processes must be in 2..batch_size ({batch_size}), got {processes!r}")
        parts = BatchPart.split(batch_size, processes)
        options: dict[str, Any] = {"scene_kwargs": scene_kwargs, "reward": reward, "adr": adr}
        #: The first part, simulated in this process.
        self.local = TaskSimulator(task, part=parts[0], **options)
        self.task, self.batch_size, self.parts = task, batch_size, parts
        self.robot, self.n_joints, self.horizon = self.local.robot, self.local.n_joints, self.local.horizon
        self.action_scale = self.local.action_scale
        self.observation_size, self.adr, self.dt = self.local.observation_size, adr, self.local.dt
        self.scene_kwargs, self.reward = scene_kwargs, reward
        context = multiprocessing.get_context("spawn")
        self._connections: list[Connection] = []
        self._processes: list[Any] = []
        self._buffers: list[SharedBuffers] = []
        try:
            for part in parts[1:]:
                path = tempfile.mktemp(prefix=f"toolimit-{os.getpid()}-", dir=SHARED_DIR)
                buffers = SharedBuffers(path, part.size, self.n_joints, self.observation_size, create=True)
                try:
                    ours, theirs = context.Pipe()
                    process = context.Process(target=_serve, args=(theirs, task, part, options, path), daemon=True)
                    with starting_processes():
                        process.start()
                    theirs.close()
                    self._connections.append(ours)
                    self._processes.append(process)
                    self._buffers.append(buffers)
                    self._wait([ours])  # the worker has mapped the buffer ...
                finally:
                    os.unlink(path)  # ... which now lives as long as the two mappings
        except BaseException:
            self.close()
            raise

    # --------------------------------------------------------------------------------- episode
    @property
    def adr_bounds(self) -> Any:
        return self.local.adr_bounds

    @property
    def t(self) -> int:
        return self.local.t

    @property
    def done(self) -> bool:
        return self.local.done

    @property
    def q(self) -> np.ndarray:
        """(B, N) joints, rad."""
        return np.concatenate([self.local.q, *(buffers.q for buffers in self._buffers)])

    def copy(self, **changes: Any) -> TaskSimulator:
        """A TaskSimulator of the whole batch (one process), as TaskSimulator.copy makes one."""
        kwargs = {"batch_size": self.batch_size, "scene_kwargs": self.scene_kwargs, "reward": self.reward}
        return TaskSimulator(self.task, **(kwargs | {"adr": self.adr} | changes))

    def reset(self, rng: np.random.Generator, box_positions: np.ndarray | None = None) -> np.ndarray:
        """TaskSimulator.reset over all parts; ``rng`` ends as one process leaves it."""
        message = _RESET + pickle.dumps((rng.bit_generator.state, box_positions, self.local.adr_bounds))
        for connection in self._connections:
            connection.send_bytes(message)
        first = self.local.reset(rng, box_positions)
        self._wait(self._connections)
        return np.concatenate([first, *(self._observations_of(buffers) for buffers in self._buffers)])

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """TaskSimulator.step over all parts, the workers' parts while this process steps its own."""
        actions = np.asarray(actions, dtype=float).reshape(self.batch_size, self.n_joints)
        for part, buffers, connection in zip(self.parts[1:], self._buffers, self._connections):
            buffers.actions[:] = part.of(actions)
            connection.send_bytes(_STEP)
        observations, rewards, goals = self.local.step(self.parts[0].of(actions))
        self._wait(self._connections)
        return (
            np.concatenate([observations, *(self._observations_of(buffers) for buffers in self._buffers)]),
            np.concatenate([rewards, *(buffers.rewards for buffers in self._buffers)]),
            np.concatenate([goals, *(buffers.goals for buffers in self._buffers)]),
        )

    def is_success(self) -> np.ndarray:
        """(B,) the paper's success test over the steps so far."""
        return np.concatenate([self.local.is_success(), *(buffers.success > 0.5 for buffers in self._buffers)])

    def tracking_action(self) -> np.ndarray:
        """(B, N) the tracking controller's actions (TaskSimulator.tracking_action)."""
        return self.local.tracking_action(self.q)

    @staticmethod
    def _observations_of(buffers: SharedBuffers) -> np.ndarray:
        return buffers.observations.astype(np.float32)

    def _wait(self, connections: list[Connection]) -> None:
        """One answer from each of ``connections``; RuntimeError with a worker's traceback if it failed."""
        for connection in connections:
            try:
                answer = connection.recv_bytes()
            except (EOFError, OSError) as error:
                raise RuntimeError("a simulation worker process ended unexpectedly") from error
            if answer != _DONE:
                raise RuntimeError("a simulation worker failed:\n" + answer[1:].decode())

    # ---------------------------------------------------------------------------------- closing
    def close(self) -> None:
        """End the workers (quit message, then SIGTERM, then SIGKILL) and unmap the buffers."""
        for connection in self._connections:
            with contextlib.suppress(OSError):  # already gone
                connection.send_bytes(_QUIT)
        for process in self._processes:
            process.join(QUIT_WAIT_S)
            if process.is_alive():
                process.terminate()
                process.join(TERMINATE_WAIT_S)
            if process.is_alive():
                process.kill()
                process.join()
        for connection in self._connections:
            connection.close()
        for buffers in self._buffers:
            buffers.close()
        self._connections, self._processes, self._buffers = [], [], []
