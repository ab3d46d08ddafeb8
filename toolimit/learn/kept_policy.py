"""The kept policy: a run's final policy is its best early-stopping check's, when it does better
than the last update's on episodes that chose neither.

PPO's policy does not improve monotonically. On the Panda scythe (``scythe_01``, seed 0, the
`authors` preset) the checks' deterministic success was 0.8-1.0 from 0.3 to 1.5 M steps and
0.25-0.5 from 5 M on; the last update's policy at 14 M succeeded in 5 of 20 evaluation episodes,
against 20 of 20 at 1.5 M. The checks (:mod:`toolimit.learn.early_stop`) roll the policy's mean
out on seeds of their own, apart from the final evaluation's, so keeping the best-checked policy is
model selection on held-out episodes.

The best check is the one with the highest success rate, the latest among equals: a run that stopped
early keeps the policy of the check it stopped on, and a run whose checks never succeed keeps its
last check's. Its model is saved the moment it is found (``best-<steps>.safetensors``, named in
``best.json`` with its check's outcome, the older file removed once the record is written), so that
an interrupted run resumes with it.

The best of a long run's thousands of 20-episode checks flatters its policy: on ``scythe_04`` the
best check (0.90, at 13.58 M steps) was of a policy that succeeded in 8 of 20 evaluation episodes,
where the last update's succeeded in 14. So at the end of a run whose best check is not its last
update, both policies are rolled out on ``episodes`` deterministic episodes of their own
(:data:`SELECTION_SEED`), and the best check's is kept only when it does better there (success,
then goal reward); the last update's otherwise. Two candidates judged on 200 fresh episodes leave
little to flatter, and the final evaluation's episodes still chose nothing.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any, cast

from stable_baselines3 import PPO
from stable_baselines3.common.base_class import BaseAlgorithm

from toolimit.artifacts import atomic_path, inside_folder, save_json
from toolimit.learn.evaluate import evaluate
from toolimit.learn.policy_file import MODEL_SUFFIX, load_model, save_model
from toolimit.learn.task import LearningTask

#: The record of the kept check: its PPO steps, its outcome and its model's file.
BEST_JSON = "best.json"
#: Seed of the episodes that choose between the best check's policy and the last update's: apart
#: from the training's (0, 1, ...), the checks' (2000 + update) and the final evaluation's (1000).
SELECTION_SEED = 1_000_000


def selection_outcome(
    model: BaseAlgorithm, task: LearningTask, episodes: int, scene_kwargs: dict[str, Any] | None
) -> dict[str, float]:
    """``model``'s success rate and mean goal reward over ``episodes`` deterministic episodes of
    ``task`` from :data:`SELECTION_SEED`."""
    outcome = evaluate(model, task, episodes, deterministic=True, seed=SELECTION_SEED, scene_kwargs=scene_kwargs)
    record = outcome.record()
    return {"success_rate": record["success_rate"], "goal_reward_mean": record["goal_reward_mean"]}


class KeptPolicy:
    """The best check's model of a run in ``directory``, and the final choice between it and the
    last update's (module docstring): on ``episodes`` episodes of ``task`` in a scene built with
    ``scene_kwargs``."""

    def __init__(self, directory: Path, task: LearningTask, episodes: int, scene_kwargs: dict[str, Any] | None = None):
        self.directory = directory
        self.task = task
        self.episodes = episodes
        self.scene_kwargs = scene_kwargs
        path = directory / BEST_JSON
        #: The kept check (``env_steps``, ``success_rate``, ``goal_reward_mean``, ``model``), or
        #: None before the first check.
        self.record: dict[str, Any] | None = json.loads(path.read_text()) if path.is_file() else None
        if self.record is not None:  # a planted name must not make the bookkeeping read or delete outside
            inside_folder(directory, self.record.get("model"), f"{path}: model")

    def offer(self, model: BaseAlgorithm, env_steps: int, success_rate: float, goal_reward_mean: float) -> bool:
        """Keep ``model`` (checked at ``env_steps`` with that outcome) if its success is at least
        the kept one's; whether it was kept."""
        if self.record is not None and success_rate < self.record["success_rate"]:
            return False
        name = f"best-{env_steps}{MODEL_SUFFIX}"
        save_model(cast(PPO, model), self.directory / name)
        previous = self.record
        self.record = {
            "env_steps": int(env_steps),
            "success_rate": float(success_rate),
            "goal_reward_mean": float(goal_reward_mean),
            "model": name,
        }
        save_json(self.directory / BEST_JSON, self.record)
        if previous is not None and previous["model"] != name:
            inside_folder(self.directory, previous["model"], f"{self.directory / BEST_JSON}: model").unlink(
                missing_ok=True
            )
        return True

    def install(self, policy_file: Path, last_model: PPO, last_file: Path) -> tuple[PPO, dict[str, Any]]:
        """Copy the run's policy to ``policy_file``: the best check's or the last update's
        (``last_model``, saved as ``last_file``), chosen as the module docstring says; the last
        update's when no check was made (a budget shorter than the checks' interval). Returns its
        model with the choice's record for ``learning.json``: ``policy`` (``best_check`` or
        ``last_update``), its ``env_steps``, the ``best_check`` and, when the two were rolled out,
        ``selection`` (each one's outcome, the episodes and their seed)."""
        last_steps = int(last_model.num_timesteps)
        choice: dict[str, Any] = {"policy": "last_update", "env_steps": last_steps, "best_check": self.record}
        policy, source = last_model, last_file
        if self.record is not None:
            best_file = inside_folder(self.directory, self.record["model"], f"{self.directory / BEST_JSON}: model")
            best_wins = self.record["env_steps"] == last_steps  # the same policy: nothing to choose
            if not best_wins:
                best_model = load_model(best_file)
                outcomes = {
                    "best_check": selection_outcome(best_model, self.task, self.episodes, self.scene_kwargs),
                    "last_update": selection_outcome(last_model, self.task, self.episodes, self.scene_kwargs),
                }
                ranked = {name: (o["success_rate"], o["goal_reward_mean"]) for name, o in outcomes.items()}
                best_wins = ranked["best_check"] > ranked["last_update"]
                choice["selection"] = outcomes | {"episodes": self.episodes, "seed": SELECTION_SEED}
                policy = best_model if best_wins else last_model
            if best_wins:
                choice |= {"policy": "best_check", "env_steps": int(self.record["env_steps"])}
                source = best_file
        with atomic_path(policy_file) as tmp:
            shutil.copyfile(source, tmp)
        return policy, choice
