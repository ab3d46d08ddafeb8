"""Open-loop execution of an exported joint trajectory in the learning task's scene.

The paper's last step computes the policy's joint trajectory offline and streams it to the real
Panda with no policy in the loop. This replays an export the same way in simulation: the joints
follow the exported commands as a position-controlled arm tracks them (exactly, sampled at the
scene's control steps, between two commands by linear interpolation, the last one held after the
end), in the task's scene from the learning task's seeded resets, with their noise on every scene
position. The arm stands at the commands' first sample when they start (a robot is moved to a
trajectory's start before it runs it), so only the start joints' reset noise goes unused.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from toolimit.errors import InputError
from toolimit.learn.evaluate import EVALUATION_SEED
from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.task import LearningTask

#: Episodes an export is replayed for by default, as many as a policy's evaluation.
OPEN_LOOP_EPISODES = 20


@dataclass(frozen=True)
class OpenLoopResult:
    """Outcome of :func:`replay_open_loop`.

    Attributes:
        goal_rewards: (E,) goal reward at each episode's last step (spade: spheres in the box).
        successes: (E,) the paper's success criterion per episode (the timed rules included).
        duration: the commands' duration, s; horizon: the episode's, s.
    """

    goal_rewards: np.ndarray
    successes: np.ndarray
    duration: float
    horizon: float

    def record(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "episodes": len(self.successes),
            "success_rate": float(np.mean(self.successes)),
            "goal_reward_mean": float(np.mean(self.goal_rewards)),
            "goal_reward": self.goal_rewards.tolist(),
            "successes": self.successes.tolist(),
            "commands_duration_s": self.duration,
            "episode_duration_s": self.horizon,
        }


def commands_at(times: np.ndarray, positions: np.ndarray, at: np.ndarray) -> np.ndarray:
    """(M, N) joint positions (rad) commanded at the times ``at`` (M,) s, from commands
    ``positions`` (K, N) rad at increasing ``times`` (K,) s: linear between two, the first before
    the start, the last after the end."""
    return np.stack([np.interp(at, times, positions[:, j]) for j in range(positions.shape[1])], axis=1)


def replay_open_loop(
    times: np.ndarray,
    positions: np.ndarray,
    task: LearningTask,
    episodes: int = OPEN_LOOP_EPISODES,
    seed: int = EVALUATION_SEED,
    scene_kwargs: dict[str, Any] | None = None,
) -> OpenLoopResult:
    """Replay joint commands ``positions`` (K, N) rad at ``times`` (K,) s (from 0) in ``task``'s
    scene for ``episodes`` episodes of its horizon, from the resets a policy's evaluation with
    ``seed`` starts from (module docstring)."""
    times, positions = np.asarray(times, dtype=float), np.asarray(positions, dtype=float)
    if positions.ndim != 2 or positions.shape != (len(times), len(task.joint_names)) or len(times) < 2:
        raise InputError(
            f"commands must be (K, {len(task.joint_names)}) positions at K >= 2 times, got {positions.shape} "
            f"at {times.shape}"
        )
    if not (np.all(np.isfinite(positions)) and np.all(np.diff(times) > 0)):
        raise InputError("commands must be finite positions at increasing times")
    if episodes < 1:
        raise InputError(f"episodes must be >= 1, got {episodes!r}")
    simulator = TaskSimulator(task, batch_size=episodes, scene_kwargs=scene_kwargs)
    simulator.reset(np.random.default_rng(seed), start=positions[0])
    goal = np.zeros(episodes)
    steps = commands_at(times, positions, np.arange(1, task.horizon + 1) * task.control_dt)
    for q in steps:
        goal = simulator.move_to(np.tile(q, (episodes, 1)))
    return OpenLoopResult(goal, simulator.is_success(), float(times[-1]), task.horizon * task.control_dt)
