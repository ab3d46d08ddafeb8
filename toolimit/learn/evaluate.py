"""Evaluation of a policy: rollouts over many seeds, goal reward and the paper's success rate.

Deterministic rollouts act with the policy's mean; stochastic ones sample its Gaussian (how PPO
explores). All episodes of one evaluation run at once in one batched scene.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm

from toolimit.learn.task import LearningTask
from toolimit.learn.vec_env import BatchedTaskVecEnv


@dataclass(frozen=True)
class Evaluation:
    """Outcome of :func:`evaluate`.

    Attributes:
        deterministic: whether the policy's mean was used.
        goal_rewards: (E,) goal reward at each episode's last step (spade: spheres in the box).
        successes: (E,) the paper's success criterion per episode.
        returns: (E,) episode returns (sum of the per-step rewards).
        joint_positions: (E, H+1, N) joint trajectories, rad (for views and export).
    """

    deterministic: bool
    goal_rewards: np.ndarray
    successes: np.ndarray
    returns: np.ndarray
    joint_positions: np.ndarray

    def record(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "deterministic": self.deterministic, "episodes": len(self.successes),
            "success_rate": float(np.mean(self.successes)), "goal_reward_mean": float(np.mean(self.goal_rewards)),
            "goal_reward": self.goal_rewards.tolist(), "return_mean": float(np.mean(self.returns)),
        }


def evaluate(model: BaseAlgorithm, task: LearningTask, episodes: int = 20, deterministic: bool = True,
             seed: int = 1000, scene_kwargs: dict[str, Any] | None = None) -> Evaluation:
    """Roll ``model``'s policy out for ``episodes`` episodes of ``task`` (one batch, seeded)."""
    env = BatchedTaskVecEnv(task, episodes, seed=seed, scene_kwargs=scene_kwargs)
    observation = env.reset()
    joints = [env.simulator.q.copy()]
    returns = np.zeros(episodes)
    while True:
        action, _ = model.predict(observation, deterministic=deterministic)
        observation, reward, done, infos = env.step(action)
        returns += reward
        if done[0]:
            joints.append(np.array([info["terminal_joints"] for info in infos]))
            break
        joints.append(env.simulator.q.copy())
    return Evaluation(deterministic, np.array([info["goal_reward"] for info in infos]),
                      np.array([info["is_success"] for info in infos]), returns, np.stack(joints, axis=1))
