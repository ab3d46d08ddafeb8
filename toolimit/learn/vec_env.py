"""B instances of a task as one stable-baselines3 ``VecEnv``: one vectorised physics step for all.

SB3's ``DummyVecEnv`` would step B Gymnasium environments one after the other, each with its own
scene; here the scene is batched (:mod:`toolimit.scenes.base`), so the B instances share every
physics call. All episodes have the task's horizon H and start together, so they also end and
reset together.

At the horizon the episode ends: ``dones`` is True and each ``info`` has ``terminal_observation``,
``terminal_joints`` (N,) rad,
``is_success`` (the paper's criterion) and ``episode`` (return ``r``, length ``l``, time ``t``, as
SB3's Monitor writes it, so that PPO logs returns and success rates). ``TimeLimit.truncated`` is
False: the time is part of the observation and nothing happens after H, so the value of the last
state is zero and PPO must not bootstrap past it (a finite-horizon task, as the authors trained it).

With ``processes`` > 1 the B instances are stepped by that many processes at once, each a part of
the batch (:class:`~toolimit.learn.split_simulator.SplitSimulator`: shared buffers, no pickling
per step; 3D scenes); the numbers are those of one process. ``close`` ends the worker processes.

With ``adr=True`` each instance's goal box is drawn inside the ADR bounds at every reset (one
position per instance) and observed; ``adr`` holds the bounds and the boundary tests' generator
(:class:`toolimit.learn.adr.AdrState`, seeded from ``seed``), which checkpoints save.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnvIndices

from toolimit.learn.adr import ADR_STREAM, AdrState
from toolimit.learn.env import action_space, observation_space
from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.split_simulator import SplitSimulator
from toolimit.learn.task import LearningTask


class BatchedTaskVecEnv(VecEnv):
    """B instances of ``task`` (see the module docstring).

    Args:
        task: the learning task.
        num_envs: B.
        seed: seed of the generator behind every reset (``VecEnv.seed`` replaces it).
        scene_kwargs: keyword arguments of the scene's constructor.
        reward: ``"sparse"`` or ``"dense"`` (:data:`toolimit.learn.simulator.REWARDS`).
        adr: domain randomisation of the goal box (module docstring).
        processes: processes stepping the instances (module docstring).
    """

    def __init__(
        self,
        task: LearningTask,
        num_envs: int,
        seed: int = 0,
        scene_kwargs: dict[str, Any] | None = None,
        reward: str = "sparse",
        adr: bool = False,
        processes: int = 1,
    ):
        self.simulator: TaskSimulator | SplitSimulator = (
            TaskSimulator(task, batch_size=num_envs, scene_kwargs=scene_kwargs, reward=reward, adr=adr)
            if processes == 1
            else SplitSimulator(task, num_envs, processes, scene_kwargs=scene_kwargs, reward=reward, adr=adr)
        )
        bounds = self.simulator.adr_bounds
        self.adr = None if bounds is None else AdrState(bounds, np.random.default_rng([seed, ADR_STREAM]))
        self.task = task
        self.render_mode = None
        spaces = self.simulator if isinstance(self.simulator, TaskSimulator) else self.simulator.local
        super().__init__(num_envs, observation_space(spaces), action_space(spaces))
        self._rng = np.random.default_rng(seed)
        #: The generator's state just before the latest reset (a checkpoint restores it).
        self.rng_state_at_reset: Mapping[str, Any] = self._rng.bit_generator.state
        self._actions = np.zeros((num_envs, self.simulator.n_joints))
        self._returns = np.zeros(num_envs)
        self._goal = np.zeros(num_envs)
        self._episode_start = time.perf_counter()
        #: Seconds spent in the simulator (physics, kinematics) since construction.
        self.simulation_time_s = 0.0

    def reset(self) -> np.ndarray:
        if self._seeds[0] is not None:
            self._rng = np.random.default_rng(self._seeds[0])
        self._reset_seeds()
        self.rng_state_at_reset = self._rng.bit_generator.state
        self._returns[:] = 0.0
        self._episode_start = started = time.perf_counter()
        observations = self.simulator.reset(self._rng)
        self.simulation_time_s += time.perf_counter() - started
        return observations

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=float)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        started = time.perf_counter()
        observations, rewards, goal = self.simulator.step(self._actions)
        self.simulation_time_s += time.perf_counter() - started
        self._returns += rewards
        self._goal = goal
        infos: list[dict[str, Any]] = [{"goal_reward": float(g)} for g in goal]
        done = self.simulator.done
        if done:
            success = self.simulator.is_success()
            elapsed = time.perf_counter() - self._episode_start
            joints = self.simulator.q.copy()
            for i, info in enumerate(infos):
                info.update(
                    terminal_observation=observations[i],
                    terminal_joints=joints[i],
                    is_success=bool(success[i]),
                    episode={"r": float(self._returns[i]), "l": self.simulator.t, "t": elapsed},
                    **{"TimeLimit.truncated": False},
                )
            observations = self.reset()
        return observations, rewards.astype(np.float32), np.full(self.num_envs, done), infos

    def restore_rng_state(self, state: dict[str, Any]) -> None:
        """Make the next reset draw exactly as the reset that ``rng_state_at_reset`` was taken before."""
        self._reset_seeds()
        self._rng.bit_generator.state = state

    def tracking_action(self) -> np.ndarray:
        """(B, N) the tracking controller's actions now (see TaskSimulator.tracking_action)."""
        return self.simulator.tracking_action()

    def close(self) -> None:
        if isinstance(self.simulator, SplitSimulator):
            self.simulator.close()

    # SB3's attribute access: every instance shares this object's attributes.
    def _count(self, indices: VecEnvIndices) -> int:
        return len(list(self._get_indices(indices)))

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return [getattr(self, attr_name)] * self._count(indices)

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **method_kwargs: Any
    ) -> list[Any]:
        return [getattr(self, method_name)(*method_args, **method_kwargs)] * self._count(indices)

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        return [False] * self._count(indices)
