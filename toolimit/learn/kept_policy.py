"""The kept policy: a run's final policy is the one of its best early-stopping check.

PPO's policy does not improve monotonically. On the Panda scythe (``scythe_01``, seed 0, the
`authors` preset) the checks' deterministic success was 0.8-1.0 from 0.3 to 1.5 M steps and
0.25-0.5 from 5 M on; the last update's policy at 14 M succeeded in 5 of 20 evaluation episodes,
against 20 of 20 at 1.5 M. The checks (:mod:`toolimit.learn.early_stop`) roll the policy's mean
out on seeds of their own, apart from the final evaluation's, so keeping the best-checked policy is
model selection on held-out episodes: the final evaluation still judges it on episodes that did not
choose it.

The best check is the one with the highest success rate, the latest among equals: a run that stopped
early keeps the policy of the check it stopped on, and a run whose checks never succeed keeps its
last check's. Its model is saved the moment it is found (``best-<steps>.zip``, named in
``best.json`` with its check's outcome, the older file removed once the record is written), so that
an interrupted run resumes with it.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

from stable_baselines3 import PPO
from stable_baselines3.common.base_class import BaseAlgorithm

from toolimit.artifacts import atomic_path, save_json

#: The record of the kept check: its PPO steps, its outcome and its model's file.
BEST_JSON = "best.json"


class KeptPolicy:
    """The best check's model of a run in ``directory`` (module docstring)."""

    def __init__(self, directory: Path):
        self.directory = directory
        path = directory / BEST_JSON
        #: The kept check (``env_steps``, ``success_rate``, ``goal_reward_mean``, ``model``), or
        #: None before the first check.
        self.record: dict[str, Any] | None = json.loads(path.read_text()) if path.is_file() else None

    def offer(self, model: BaseAlgorithm, env_steps: int, success_rate: float, goal_reward_mean: float) -> bool:
        """Keep ``model`` (checked at ``env_steps`` with that outcome) if its success is at least
        the kept one's; whether it was kept."""
        if self.record is not None and success_rate < self.record["success_rate"]:
            return False
        name = f"best-{env_steps}.zip"
        with atomic_path(self.directory / name) as tmp:
            model.save(tmp)
        previous = self.record
        self.record = {
            "env_steps": int(env_steps),
            "success_rate": float(success_rate),
            "goal_reward_mean": float(goal_reward_mean),
            "model": name,
        }
        save_json(self.directory / BEST_JSON, self.record)
        if previous is not None and previous["model"] != name:
            (self.directory / previous["model"]).unlink(missing_ok=True)
        return True

    def install(self, policy_file: Path, last_file: Path) -> PPO:
        """Copy the kept model to ``policy_file`` (the last update's, ``last_file``, when no check
        was made: a budget shorter than the checks' interval) and load it."""
        source = last_file if self.record is None else self.directory / self.record["model"]
        with atomic_path(policy_file) as tmp:
            shutil.copyfile(source, tmp)
        return PPO.load(policy_file, device="cpu")
