"""Early stopping: PPO ends once its policy has learnt the task, not when its budget runs out.

Every ``every`` updates, at an update boundary, the policy's mean is rolled out for ``episodes``
episodes of the task (the deterministic evaluation of :mod:`toolimit.learn.evaluate`) on seeds of
their own: ``CHECK_SEED + update``, apart from the training seeds (0, 1, ...) and the final
evaluation's (:data:`~toolimit.learn.evaluate.EVALUATION_SEED`), so that the episodes a run is
judged on never chose where it stopped. A check passes when that success rate reaches ``success``
and the training's own episodes since the previous check (the policy sampling its Gaussian,
``every`` updates of them) succeeded at least at ``training_success``; learning stops when ``held``
checks in a row pass. The second condition asks for a margin: a policy whose mean only just
succeeds fails under its own exploration noise, and under the small differences between machines.
Measured on the Panda spade (``spade_00``, seed 0): with the deterministic condition alone the run
stopped at 0.86 M steps with a training success of 0.56, and its final evaluation succeeded in 19 of
20 episodes (15.4 spheres; stochastic 14 of 20). A check draws nothing from the training's
generators, so a run with early stopping follows the same updates as one without, up to where it
stops.

Each check's outcome is written on the curve line of the update it judged (``check_success_rate``,
``check_goal_reward_mean``, ``check_training_success``); a resumed run reads its earlier checks and
the training's success per update back from the curve.

Under ADR success at the aligned box is not the goal, and no check is made (the ADR criterion of
the whole range is :mod:`toolimit.learn.heat_map`'s, measured after learning).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from toolimit.errors import InvalidLearningConfig
from toolimit.learn.evaluate import rollout
from toolimit.learn.kept_policy import KeptPolicy
from toolimit.learn.task import LearningTask
from toolimit.learn.vec_env import BatchedTaskVecEnv

#: Seed of the first update's check (``CHECK_SEED + update`` for each one).
CHECK_SEED = 2000
#: The curve's keys of a check's outcome.
CHECK_SUCCESS = "check_success_rate"
CHECK_GOAL = "check_goal_reward_mean"
CHECK_TRAINING = "check_training_success"


@dataclass(frozen=True)
class StopRule:
    """When PPO has learnt (module docstring).

    Attributes:
        every: PPO updates between two checks.
        episodes: deterministic episodes per check (the final evaluation's 20 by default).
        success: the success rate a check's episodes must reach.
        training_success: the success rate the training's episodes since the previous check must
            reach.
        held: checks in a row that must pass.
    """

    every: int = 10
    episodes: int = 20
    success: float = 1.0
    training_success: float = 0.8
    held: int = 2

    def __post_init__(self) -> None:
        for field in ("every", "episodes", "held"):
            value = getattr(self, field)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise InvalidLearningConfig(f"stop_{field}", f"must be an integer >= 1, got {value!r}")
        if not 0.0 < self.success <= 1.0:
            raise InvalidLearningConfig("stop_success", f"must be in (0, 1], got {self.success!r}")
        if not 0.0 <= self.training_success <= 1.0:
            raise InvalidLearningConfig("stop_training_success", f"must be in [0, 1], got {self.training_success!r}")


class EarlyStop(BaseCallback):
    """Checks the policy every ``rule.every`` updates and stops PPO once ``rule.held`` checks in a
    row passed: the policy's mean at ``rule.success``, the training's episodes since the previous
    check at ``rule.training_success`` (module docstring).

    Args:
        task: the task learnt.
        rule: the stopping rule.
        curve: the curve lines written so far (a resumed run's), whose checks count.
        scene_kwargs, reward: the training environment's (a check runs the same scene).
        kept: where each check's policy is offered (:mod:`toolimit.learn.kept_policy`); None keeps
            none.
    """

    def __init__(
        self,
        task: LearningTask,
        rule: StopRule,
        curve: Sequence[dict[str, Any]] = (),
        scene_kwargs: dict[str, Any] | None = None,
        reward: str = "sparse",
        kept: KeptPolicy | None = None,
    ):
        super().__init__()
        self.rule = rule
        self.kept = kept
        self.env = BatchedTaskVecEnv(task, rule.episodes, scene_kwargs=scene_kwargs, reward=reward)
        checks = [line for line in curve if CHECK_SUCCESS in line]
        self.passed = 0  # checks in a row that passed, up to the latest
        for line in checks:
            self.passed = self.passed + 1 if self._passes(line[CHECK_SUCCESS], line[CHECK_TRAINING]) else 0
        self.checked_steps = checks[-1]["env_steps"] if checks else -1
        #: The training episodes' success rate of each update, by PPO steps at its end (the
        #: curve's, which :meth:`add_training_success` extends as learning goes on).
        self.training: dict[int, float] = {line["env_steps"]: line["success_rate"] for line in curve}
        #: The latest check's outcome for the curve (taken by :meth:`take_record`).
        self.record: dict[str, float] = {}
        #: PPO steps when the rule was met (None while learning goes on; a resumed run that had
        #: met it is done).
        self.stopped_at: int | None = self.checked_steps if self.passed >= rule.held else None

    def _on_rollout_start(self) -> None:
        steps = self.model.num_timesteps
        per_update = self.model.n_steps * self.training_env.num_envs  # type: ignore[attr-defined]
        update = steps // per_update
        if update == 0 or update % self.rule.every or steps <= self.checked_steps:
            return
        self.env.seed(CHECK_SEED + update)
        outcome = rollout(self.model, self.env, deterministic=True).record()
        since = steps - self.rule.every * per_update
        training = float(np.mean([rate for at, rate in self.training.items() if since < at <= steps]))
        self.record = {
            CHECK_SUCCESS: outcome["success_rate"],
            CHECK_GOAL: outcome["goal_reward_mean"],
            CHECK_TRAINING: training,
        }
        self.checked_steps = steps
        if self.kept is not None:
            self.kept.offer(self.model, steps, outcome["success_rate"], outcome["goal_reward_mean"])
        self.passed = self.passed + 1 if self._passes(outcome["success_rate"], training) else 0
        if self.passed >= self.rule.held:
            self.stopped_at = steps

    def _passes(self, success: float, training: float) -> bool:
        return success >= self.rule.success and training >= self.rule.training_success

    def take_record(self) -> dict[str, float]:
        """The latest check's outcome, once (empty when no check was made since)."""
        record, self.record = self.record, {}
        return record

    def add_training_success(self, env_steps: int, success_rate: float) -> None:
        """The success rate of the training episodes of the rollout that ended at ``env_steps``."""
        self.training[env_steps] = success_rate

    def _on_step(self) -> bool:
        return self.stopped_at is None

    def _on_training_end(self) -> None:
        """Count the steps up to the update judged: SB3 stops after the first step of the next
        rollout, which PPO never learns from, so that the run ends on an update boundary and its
        final checkpoint is the state of the check."""
        if self.stopped_at is not None:
            self.model.num_timesteps = self.stopped_at
