"""The SB3 callback that runs ADR's boundary tests during PPO (the rule: :mod:`toolimit.learn.adr`).

It lives apart from the bounds (:mod:`toolimit.learn.adr`, numpy only) so that the simulator and the
environments, which draw the goal box inside the bounds, do not import the training loop that
moves them.
"""

from __future__ import annotations

from typing import cast

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback

from toolimit.learn.adr import EVERY, AdrBounds, BoundaryBatch, boundary_test
from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.vec_env import BatchedTaskVecEnv


class AdrCallback(BaseCallback):
    """Runs :func:`boundary_test` every ``every`` PPO updates, at an update's start (an episode
    boundary), on a simulator of its own; after a change the training environment is reset so that
    this update's episodes draw inside the new bounds, and a checkpoint taken next (after this
    callback) resumes exactly.

    Args:
        env: the training environment (``adr=True``); its ``adr`` state is what the tests change.
        every: updates between tests.
    """

    def __init__(self, env: BatchedTaskVecEnv, every: int = EVERY):
        super().__init__()
        if every < 1:
            raise ValueError(f"every must be >= 1 update, got {every!r}")
        if env.adr is None:
            raise ValueError("the environment has no ADR (make it with adr=True)")
        self.env, self.state, self.every = env, env.adr, every
        self.simulator: TaskSimulator = env.simulator.copy(adr=True)

    def _on_rollout_start(self) -> None:
        steps = self.model.n_steps * self.env.num_envs  # type: ignore[attr-defined]
        update = self.model.num_timesteps // steps
        if update == 0 or update % self.every or self.state.tested_at >= update:
            return
        record = boundary_test(self.state, self._episodes_at, self._placeable)
        self.state.tested_at = update
        if record["after"] != record["bound"]:
            self.model._last_obs = self.env.reset()  # type: ignore[attr-defined]
            self.model._last_episode_starts = np.ones(self.env.num_envs, dtype=bool)  # type: ignore[attr-defined]

    def _placeable(self, bounds: AdrBounds) -> bool:
        return bounds.placeable(self.state.rng, self.simulator.box_validity(self.simulator.task.params))

    def _episodes_at(self, bounds: AdrBounds) -> BoundaryBatch:
        """One batch of episodes with the box drawn inside ``bounds``: each one's success (the
        scene's test), whether its box stood inside ``bounds`` (not at the aligned fallback) and the
        mean goal reward; the policy's mean plus its Gaussian noise, drawn
        from the ADR generator (torch's stays untouched)."""
        simulator, rng = self.simulator, self.state.rng
        simulator.adr_bounds = bounds
        policy = self.model.policy
        std = torch.exp(cast(torch.Tensor, policy.log_std)).detach().numpy()
        observation = simulator.reset(rng)
        placed = simulator.box_placed.copy()
        goal = np.zeros(simulator.batch_size)
        while not simulator.done:
            mean, _ = policy.predict(observation, deterministic=True)
            action = np.clip(mean + std * rng.normal(size=mean.shape), -1.0, 1.0)
            observation, _, goal = simulator.step(action)
        return BoundaryBatch(simulator.is_success(), placed, float(goal.mean()))

    def _on_step(self) -> bool:
        return True
