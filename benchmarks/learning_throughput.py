"""Training throughput of stage iv next to stable-baselines3's own ceiling, measured in the same run.

Training: ``PPO.learn`` on the task's :class:`~toolimit.learn.BatchedTaskVecEnv` with the project's
PPO (:func:`toolimit.learn.ppo.make_ppo`: 400-300 tanh policy and value, the preset's epochs and
minibatches, one rollout = whole episodes), as ``learn_policy`` runs it after cloning.
Ceiling: the same PPO (same networks, number of environments, rollout length, batch size, epochs)
on a trivial ``VecEnv`` of the same observation and action sizes and episode length whose step
returns zeros and costs nothing: the most env steps per second SB3 itself reaches on this machine.
The ratio training / ceiling says how much the simulation costs on top of the learner.

Both are timed after one untimed warm-up update each (PPO's set-up, torch's first calls),
``--repeats`` times, interleaved, and the fastest run of each is kept (the machine is shared). The
time split comes from a timing wrapper around the VecEnv (simulation: inside ``reset``/``step``,
the wait for the second process included), the rollout callbacks (policy inference and buffer: the rest of
the rollout collection) and the remainder (``train()``: the gradient updates).

Options explored (see the figures in the lead's closing note of issue 10):
``--threads N`` sets ``torch.set_num_threads`` for both runs (default 1: on the 2 cores shared with
other jobs, torch's default of one thread per core was 4-9x slower for these small networks, the
ceiling included; with a core free, 2 threads were 1.3x (training) to 1.5x (ceiling) faster for
1.5-1.7x the CPU, which lowers the ratio: the simulation is single-threaded);
``--processes K`` steps the B instances in K processes, the library's
:class:`~toolimit.learn.split_simulator.SplitSimulator` (shared buffers, one byte on a pipe per
step and worker; the same numbers as one process): on the Panda spade, 5,294 against 5,853
steps/s for one process with the second core busy with other jobs (load average about 3); an
earlier version of this option (pipes, pickled results per step) was no faster either;
``--sim-threads N`` shares the 3D spade's instances out among N numba threads inside each process
(the scene keyword ``threads``; the same numbers bit for bit).

Prints steps per second (wall clock; CPU seconds of the main process alongside), the split, writes
``benchmarks/results/learning_throughput_<name>.json`` and ends with ``ratio R``. Keep the budget
small on a shared machine, e.g.:

    nice -n 5 python benchmarks/learning_throughput.py                      # the Panda spade (3D)
    nice -n 5 python benchmarks/learning_throughput.py --env toolimit/SpadePlanar-v0 --threads 0
    nice -n 5 python benchmarks/learning_throughput.py --env toolimit/Spade3D-v0 --processes 1
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

from toolimit.artifacts import save_json
from toolimit.learn import BatchedTaskVecEnv, LearningTask, TaskSimulator, shipped_task
from toolimit.learn.env import ENV_TOOLS, ENV_WORLDS, action_space, env_id, observation_space
from toolimit.learn.ppo import PRESETS, make_ppo

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "benchmarks" / "results"
DEFAULT_ENV = "toolimit/Spade3D-v0"
FALLBACK_ENV = "toolimit/Hammer3D-v0"


# ------------------------------------------------------------------------------------ the envs
class TrivialVecEnv(VecEnv):
    """B instances of nothing: zero observations and rewards, episodes of ``horizon`` steps with the
    infos BatchedTaskVecEnv gives at their end (so SB3's own bookkeeping is the same). ``simulator``
    carries what :func:`make_ppo` reads (horizon, velocity limits)."""

    def __init__(self, like: TaskSimulator, num_envs: int):
        self.render_mode = None
        super().__init__(num_envs, observation_space(like), action_space(like))
        self.simulator = SimpleNamespace(horizon=like.horizon, robot=SimpleNamespace(velocity_limit=like.robot.velocity_limit))
        self._observation = np.zeros((num_envs, like.observation_size), dtype=np.float32)
        self._t = 0

    def reset(self) -> np.ndarray:
        self._t = 0
        return self._observation.copy()

    def step_async(self, actions: np.ndarray) -> None:
        pass

    def step_wait(self):
        self._t += 1
        rewards = np.zeros(self.num_envs, dtype=np.float32)
        infos: list[dict[str, Any]] = [{"goal_reward": 0.0} for _ in range(self.num_envs)]
        done = self._t >= self.simulator.horizon
        if done:
            for info in infos:
                info.update(terminal_observation=self._observation[0], is_success=False,
                            episode={"r": 0.0, "l": self._t, "t": 0.0}, **{"TimeLimit.truncated": False})
            self._t = 0
        return self._observation.copy(), rewards, np.full(self.num_envs, done), infos

    def close(self) -> None:
        pass

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        return [getattr(self, attr_name)] * len(self._get_indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        setattr(self, attr_name, value)

    def env_method(self, method_name: str, *args: Any, indices: Any = None, **kwargs: Any) -> list[Any]:
        return [getattr(self, method_name)(*args, **kwargs)] * len(self._get_indices(indices))

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(self._get_indices(indices))


class StepTimer(VecEnvWrapper):
    """Counts the wall seconds PPO spends inside the wrapped VecEnv (reset and step)."""

    def __init__(self, venv: VecEnv):
        super().__init__(venv)
        self.seconds = 0.0

    def reset(self) -> np.ndarray:
        started = time.perf_counter()
        observations = self.venv.reset()
        self.seconds += time.perf_counter() - started
        return observations

    def step_async(self, actions: np.ndarray) -> None:
        started = time.perf_counter()
        self.venv.step_async(actions)
        self.seconds += time.perf_counter() - started

    def step_wait(self):
        started = time.perf_counter()
        result = self.venv.step_wait()
        self.seconds += time.perf_counter() - started
        return result


class RolloutTimer(BaseCallback):
    """Wall seconds of rollout collection (the rest of ``learn`` is ``train()``)."""

    def __init__(self) -> None:
        super().__init__()
        self.seconds, self._started = 0.0, 0.0

    def _on_rollout_start(self) -> None:
        self._started = time.perf_counter()

    def _on_rollout_end(self) -> None:
        self.seconds += time.perf_counter() - self._started

    def _on_step(self) -> bool:
        return True


# --------------------------------------------------------------------------------- measurement
@dataclass(frozen=True)
class Throughput:
    """One timed ``PPO.learn``: steps, wall and main-process CPU seconds, and the wall split."""

    steps: int
    wall_s: float
    cpu_s: float
    env_s: float
    inference_s: float
    update_s: float

    @property
    def steps_per_s(self) -> float:
        return self.steps / self.wall_s

    def record(self) -> dict[str, float]:
        return {"steps": self.steps, "steps_per_s": self.steps_per_s, "wall_s": self.wall_s, "cpu_s": self.cpu_s,
                "env_s": self.env_s, "inference_s": self.inference_s, "update_s": self.update_s}


class Learner:
    """The project's PPO on ``env`` (behind a :class:`StepTimer`), warmed up by one untimed update.

    The preset's early stop on the KL (``target_kl``) is switched off, so that the training and
    the ceiling do the same gradient steps per update whatever their data."""

    def __init__(self, env: VecEnv, preset: str, seed: int):
        self.timed = StepTimer(env)
        settings = replace(PRESETS[preset], target_kl=None)
        self.model = make_ppo(self.timed, settings, seed=seed)  # type: ignore[arg-type]
        self.per_update = self.model.n_steps * env.num_envs
        self.model.learn(self.per_update)

    def time(self, timesteps: int) -> Throughput:
        """One timed PPO.learn of ``timesteps`` steps rounded up to whole updates."""
        updates = max(1, -(-timesteps // self.per_update))
        timer = RolloutTimer()
        self.timed.seconds = 0.0
        wall, cpu = time.perf_counter(), time.process_time()
        self.model.learn(updates * self.per_update, callback=timer, reset_num_timesteps=False)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        return Throughput(updates * self.per_update, wall, cpu, self.timed.seconds,
                          timer.seconds - self.timed.seconds, wall - timer.seconds)


def fastest(runs: list[Throughput]) -> Throughput:
    """The run least disturbed by other processes (the highest rate)."""
    return max(runs, key=lambda run: run.steps_per_s)


def load_task(args: argparse.Namespace) -> tuple[str, LearningTask]:
    """(name, task) of --task or --env; the 3D spade falls back to the 3D hammer when not shipped."""
    if args.task is not None:
        return args.task.stem, LearningTask.load(args.task)
    ids = {env_id(tool, world): (tool, world) for tool in ENV_TOOLS for world in ENV_WORLDS}
    if args.env not in ids:
        sys.exit(f"--env: unknown id {args.env!r}; known: {', '.join(sorted(ids))}")
    name = args.env
    try:
        task = shipped_task(*ids[name])
    except ValueError as error:
        if name != DEFAULT_ENV:
            sys.exit(f"--env: {error}")
        print(f"{DEFAULT_ENV} has no shipped task yet ({error.args[0].split(';')[0]}); "
              f"measuring {FALLBACK_ENV} instead (the same Panda, a 3D world)")
        name = FALLBACK_ENV
        task = shipped_task(*ids[name])
    return name.removeprefix("toolimit/").removesuffix("-v0"), task


def _split(label: str, t: Throughput) -> str:
    def share(seconds: float) -> float:
        return 100 * seconds / t.wall_s

    return (f"{label}: {t.steps_per_s:7.0f} env steps/s ({t.steps} steps, {t.wall_s:.1f} s wall, {t.cpu_s:.1f} s CPU "
            f"main process); simulation {share(t.env_s):.0f} %, policy inference {share(t.inference_s):.0f} %, "
            f"PPO updates {share(t.update_s):.0f} %")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--env", default=DEFAULT_ENV, help=f"a registered id (default: {DEFAULT_ENV})")
    source.add_argument("--task", type=Path, default=None, help="a task file (task.npz) instead of --env")
    parser.add_argument("--envs", type=int, default=16, help="instances stepped together, B (default: 16)")
    parser.add_argument("--timesteps", type=int, default=10_000,
                        help="timed env steps of each run, rounded up to whole updates (default: 10000)")
    parser.add_argument("--preset", choices=sorted(PRESETS), default="toolimit", help="PPO preset (default: toolimit)")
    parser.add_argument("--threads", type=int, default=1,
                        help="torch.set_num_threads; 0 keeps torch's default of one per core (default: 1, measured "
                             "fastest)")
    parser.add_argument("--processes", type=int, default=1,
                        help="processes stepping the instances (default: 1, the library's default)")
    parser.add_argument("--sim-threads", type=int, default=1,
                        help="threads stepping the sand's instances inside each process (the 3D spade's "
                             "scene_kwargs threads; the same numbers; default: 1)")
    parser.add_argument("--repeats", type=int, default=2,
                        help="timed runs of each, interleaved; the fastest of each is kept (default: 2)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default=None,
                        help="results JSON (default: benchmarks/results/learning_throughput_<name>.json)")
    args = parser.parse_args(argv)
    if min(args.envs, args.timesteps, args.repeats) < 1 or args.threads < 0:
        sys.exit("--envs, --timesteps and --repeats must be >= 1, --threads >= 0")
    if args.threads > 0:
        torch.set_num_threads(args.threads)
    name, task = load_task(args)
    processes = args.processes
    if not 1 <= processes <= args.envs:
        sys.exit(f"--processes {processes}: must be in 1..--envs ({args.envs})")
    print(f"{name}: {task.robot} {task.tool} ({task.world}), horizon {task.horizon}, B = {args.envs}, "
          f"preset {args.preset}, torch threads {torch.get_num_threads()}, processes {processes}, "
          f"simulation threads {args.sim_threads}")

    scene_kwargs = {"threads": args.sim_threads} if args.sim_threads != 1 else None
    env = BatchedTaskVecEnv(task, args.envs, seed=args.seed, processes=processes, scene_kwargs=scene_kwargs)
    try:
        learners = Learner(env, args.preset, args.seed), \
            Learner(TrivialVecEnv(TaskSimulator(task, 1), args.envs), args.preset, args.seed)
        runs: tuple[list[Throughput], list[Throughput]] = ([], [])
        for _ in range(args.repeats):  # interleaved, so that both see the same load of the machine
            for learner, timed in zip(learners, runs):
                timed.append(learner.time(args.timesteps))
    finally:
        env.close()
    training, ceiling = fastest(runs[0]), fastest(runs[1])
    ratio = training.steps_per_s / ceiling.steps_per_s
    cpu_ratio = (training.steps / training.cpu_s) / (ceiling.steps / ceiling.cpu_s)

    print(_split("training", training))
    print(_split("ceiling ", ceiling))
    if processes == 1:  # the second process's CPU time is not the main process's (the threads' is)
        print(f"per CPU second of the main process: training / ceiling = {cpu_ratio:.2f}")
    record = {"name": name, "robot": task.robot, "tool": task.tool, "world": task.world, "horizon": task.horizon,
              "envs": args.envs, "preset": args.preset, "torch_threads": torch.get_num_threads(),
              "processes": processes, "sim_threads": args.sim_threads, "training": training.record(), "ceiling": ceiling.record(), "ratio": ratio,
              "cpu_ratio": cpu_ratio if processes == 1 else None, "repeats": args.repeats,
              "load_average": list(os.getloadavg())}
    out = Path(args.out) if args.out else RESULTS / f"learning_throughput_{name}.json"
    save_json(out, record)
    print(f"wrote {out}")
    print(f"ratio {ratio:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
