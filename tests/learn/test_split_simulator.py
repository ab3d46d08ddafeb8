"""The batch split over processes: the same rollout as one process, refusal where it cannot hold, a clean stop."""

from __future__ import annotations

import glob
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import psutil
import pytest

from toolimit.learn import BatchedTaskVecEnv, shipped_task
from toolimit.learn.batch_part import BatchPart
from toolimit.learn.split_simulator import SHARED_DIR

#: A small sand scene: the split's bookkeeping, not the physics, is under test.
FEW_SPHERES = {"n_spheres": 40}
REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def spade_3d():
    return shipped_task("spade", "3d")


def rollout(task, processes: int, steps: int, adr: bool = False) -> tuple[np.ndarray, ...]:
    """Observations, rewards and terminal infos of ``steps`` noisy tracking steps of B = 3 (a reset
    at the horizon included); under ``adr`` the goal boxes are drawn in widened bounds."""
    env = BatchedTaskVecEnv(task, 3, seed=5, scene_kwargs=FEW_SPHERES, processes=processes, adr=adr)
    if env.adr is not None:  # as a boundary test moves them: in place, in the main process
        env.adr.bounds.low[:] -= 0.1
        env.adr.bounds.high[:] += 0.1
    rng = np.random.default_rng(1)
    try:
        observations, rewards, terminal = [env.reset()], [], []
        for _ in range(steps):
            action = env.tracking_action() + rng.normal(0.0, 0.1, (3, env.simulator.n_joints))
            observation, reward, done, infos = env.step(action)
            observations.append(observation)
            rewards.append(reward)
            if done[0]:
                terminal = [(info["is_success"], info["goal_reward"], info["terminal_joints"]) for info in infos]
        return np.array(observations), np.array(rewards), np.array([t[:2] for t in terminal]), env.simulator.q
    finally:
        env.close()


def test_adr_boxes_drawn_in_moved_bounds_are_those_of_one_process(spade_3d):
    one, two = rollout(spade_3d, 1, 3, adr=True), rollout(spade_3d, 2, 3, adr=True)
    for a, b in zip(one, two):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-9)
    boxes = one[0][0, :, -2:]  # the observed goal boxes of the first reset
    assert np.ptp(boxes[:, 0]) > 1e-3  # drawn apart, per instance


def test_two_and_three_processes_give_the_one_process_rollout(spade_3d):
    steps = spade_3d.horizon + 5  # through an episode's end and the reset after it
    one = rollout(spade_3d, 1, steps)
    for processes in (2, 3):
        split = rollout(spade_3d, processes, steps)
        for a, b in zip(one, split):
            np.testing.assert_allclose(b, a, rtol=0, atol=1e-9)
    assert np.ptp(one[0][:, :, 0]) > 0.05  # the tool moved: the rollout is not trivially equal


def test_parts_cover_the_batch_in_order():
    parts = BatchPart.split(5, 2)
    assert [(p.start, p.stop, p.total) for p in parts] == [(0, 3, 5), (3, 5, 5)]
    assert BatchPart.whole(4).is_whole and not parts[1].is_whole
    with pytest.raises(ValueError, match="start < stop"):
        BatchPart(2, 2, 4)


def test_a_scene_drawing_instance_by_instance_is_refused(spade_task):
    env = BatchedTaskVecEnv(spade_task, 2, seed=0, processes=2)  # the planar spade
    try:
        with pytest.raises(ValueError, match="cannot be split over processes"):
            env.reset()
    finally:
        env.close()


STEPPING = textwrap.dedent(
    """
    import faulthandler, os, signal, sys
    from multiprocessing import resource_tracker
    import numpy as np
    from toolimit.learn import BatchedTaskVecEnv, shipped_task
    if __name__ == "__main__":
        # a script started from a terminal: Ctrl-C's default, whatever the test process has
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
        faulthandler.register(signal.SIGUSR1)  # the test asks for the stacks if the process hangs
        env = BatchedTaskVecEnv(shipped_task("spade", "3d"), 2, seed=0, scene_kwargs={"n_spheres": 20}, processes=2)
        env.reset()
        worker = env.simulator._processes[0].pid
        print(worker, resource_tracker._resource_tracker._pid, flush=True)
        while True:
            env.step(np.zeros((2, env.simulator.n_joints)))
    """
)


def alive(process: psutil.Process) -> bool:
    """Whether ``process`` runs: not ended, not a zombie (ended but not yet reaped by its parent),
    and not another process given its pid since (a busy machine reuses pids within 60 s)."""
    try:
        return process.is_running() and process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_stopped_run_leaves_no_process_nor_shared_memory(signum, tmp_path):
    """Ctrl-C (SIGINT to the whole process group, as a terminal sends it) or SIGTERM to the main
    process: the worker and multiprocessing's resource tracker end after the main process (within a
    generous 60 s: the test checks that they end, a busy machine may delay them), and the shared
    buffer's file is gone."""
    environment = {**os.environ, "PYTHONPATH": str(REPO)}
    stderr = tmp_path / "stderr.txt"
    main = subprocess.Popen(
        [sys.executable, "-c", STEPPING],
        stdout=subprocess.PIPE,
        stderr=stderr.open("w"),
        text=True,
        env=environment,
        start_new_session=True,
    )
    try:
        children = [psutil.Process(int(pid)) for pid in main.stdout.readline().split()]  # type: ignore[union-attr]
        assert len(children) == 2 and all(alive(child) for child in children)
        time.sleep(0.2)  # stepping
        if signum == signal.SIGINT:
            os.killpg(main.pid, signum)
        else:
            main.send_signal(signum)
        try:
            main.wait(timeout=60)  # its own exit (torch, numba) may take seconds on a loaded machine
        except subprocess.TimeoutExpired:
            main.send_signal(signal.SIGUSR1)
            time.sleep(1.0)
            pytest.fail(f"the main process did not end within 60 s of the signal; its stacks:\n{stderr.read_text()}")
        ended = time.monotonic()
        while any(alive(child) for child in children) and time.monotonic() - ended < 60:
            time.sleep(0.01)
        assert not [child.pid for child in children if alive(child)], "a child outlived the main process by 60 s"
        assert not glob.glob(os.path.join(SHARED_DIR, f"toolimit-{main.pid}-*"))
    finally:
        if main.poll() is None:
            main.kill()
