"""Evaluation of a policy: rollouts over many seeds, goal reward and the paper's success rate.

Deterministic rollouts act with the policy's mean; stochastic ones sample its Gaussian (how PPO
explores). All episodes of one evaluation run at once in one batched scene, each instance with its
own draw of the reset noise (:mod:`toolimit.learn.simulator`). A policy learned with
ADR (its observation holds the goal box, :mod:`toolimit.learn.adr`) is evaluated with the box at
the aligned position; :mod:`toolimit.learn.heat_map` moves it over a grid.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm

from toolimit.artifacts import save_npz
from toolimit.errors import InputError
from toolimit.learn.limit_use import LimitUse, limit_use
from toolimit.learn.simulator import observation_size
from toolimit.learn.task import LearningTask
from toolimit.learn.vec_env import BatchedTaskVecEnv
from toolimit.trajopt.result import TRAJECTORY_NPZ

#: Seed of the evaluation episodes by default: apart from the training seeds (0, 1, 2, ...).
EVALUATION_SEED = 1000


@dataclass(frozen=True)
class Evaluation:
    """Outcome of :func:`evaluate`.

    Attributes:
        deterministic: whether the policy's mean was used.
        goal_rewards: (E,) goal reward at each episode's last step (spade: spheres in the box).
        successes: (E,) the paper's success criterion per episode.
        returns: (E,) episode returns (sum of the per-step rewards).
        joint_positions: (E, H+1, N) joint trajectories, rad (for views and export).
        limits: how far the episodes' motions go past the robot's joint limits.
    """

    deterministic: bool
    goal_rewards: np.ndarray
    successes: np.ndarray
    returns: np.ndarray
    joint_positions: np.ndarray
    limits: LimitUse

    def record(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "deterministic": self.deterministic,
            "episodes": len(self.successes),
            "success_rate": float(np.mean(self.successes)),
            "goal_reward_mean": float(np.mean(self.goal_rewards)),
            "goal_reward": self.goal_rewards.tolist(),
            "return_mean": float(np.mean(self.returns)),
            "limits": self.limits.record(),
        }


def evaluate(
    model: BaseAlgorithm,
    task: LearningTask,
    episodes: int = 20,
    deterministic: bool = True,
    seed: int = EVALUATION_SEED,
    scene_kwargs: dict[str, Any] | None = None,
) -> Evaluation:
    """Roll ``model``'s policy out for ``episodes`` episodes of ``task`` (one batch, seeded)."""
    if episodes < 1:
        raise InputError(f"episodes must be >= 1, got {episodes!r}")
    env = BatchedTaskVecEnv(task, episodes, seed=seed, scene_kwargs=scene_kwargs, adr=observes_goal_box(model, task))
    return rollout(model, env, deterministic)


def rollout(model: BaseAlgorithm, env: BatchedTaskVecEnv, deterministic: bool = True) -> Evaluation:
    """One episode in each of ``env``'s instances, from its next reset (its seed decides them)."""
    observation = env.reset()
    joints = [env.simulator.q.copy()]
    returns = np.zeros(env.num_envs)
    while True:
        action, _ = model.predict(observation, deterministic=deterministic)
        stepped, reward, done, infos = env.step(action)
        observation = cast(np.ndarray, stepped)
        returns += reward
        if done[0]:
            joints.append(np.array([info["terminal_joints"] for info in infos]))
            break
        joints.append(env.simulator.q.copy())
    joint_positions = np.stack(joints, axis=1)
    return Evaluation(
        deterministic,
        np.array([info["goal_reward"] for info in infos]),
        np.array([info["is_success"] for info in infos]),
        returns,
        joint_positions,
        limit_use(joint_positions, env.task.control_dt, env.simulator.robot),
    )


def observes_goal_box(model: BaseAlgorithm, task: LearningTask) -> bool:
    """Whether ``model``'s observations hold the goal box position (it was learned with ADR)."""
    assert model.observation_space is not None and model.observation_space.shape is not None
    return model.observation_space.shape == (observation_size(len(task.joint_names), adr=True),)


def save_rollout_trajectory(joint_positions: np.ndarray, task: LearningTask, directory: str | Path) -> Path:
    """Write one rollout's joints (H+1, N) rad as ``directory/trajectory.npz`` in stage iii's format
    (q, v = diff(q) / dt, base, joint_names, dt), so that ``toolimit export`` retimes and checks it
    for open-loop execution on the real robot (the paper's last step). Returns the folder."""
    q = np.asarray(joint_positions, dtype=float)
    if q.ndim != 2 or q.shape[1] != len(task.joint_names):
        raise ValueError(f"joint_positions must be (H+1, {len(task.joint_names)}), got {q.shape}")
    directory = Path(directory)
    save_npz(
        directory / TRAJECTORY_NPZ,
        q=q,
        v=np.diff(q, axis=0) / task.control_dt,
        base=task.base,
        joint_names=np.array(task.joint_names),
        dt=np.float64(task.control_dt),
    )
    return directory
