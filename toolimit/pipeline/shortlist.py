"""Which candidate the learner starts from: the robot's replays rank the alignment's candidates, and
the best few are judged in the learning task itself.

The robot's selection (:func:`~toolimit.trajopt.selection.select_by_robot_execution`) ranks the
candidates by the mean goal reward of a few replays of the robot's trajectory, each as long as the
trajectory. What PPO starts from is another episode: the learning task's, whose horizon holds the
last configuration until the scene's success test can hold (:func:`~toolimit.learn.task.success_horizon`),
with the task's reset noise on the joints and the scene, and whose success is the paper's test, not
a mean. The two disagree near the success threshold, where the maximum of the replays' means is
decided by a few tenths of a sphere (float rounding between two CPUs moves it), and a kept
candidate can then deliver less than success asks in the learning task. So the ``size`` best
candidates by robot reward are built into their learning tasks (the learner's seed, so the same
task it will build) and their trajectories executed there by the tracking controller, the cloning's
expert, for ``episodes`` seeded episodes; the one whose tracking succeeds most often is kept (then
the higher mean goal reward, then the robot's order). This is the figure's "trajectory" measure
(:func:`toolimit.experiments.measure.measure_trajopt`), applied before learning rather than after.

The shortlist is also the learner's fall-back (:func:`toolimit.pipeline.stages.learn_stage`): a
clone may imitate well a motion too fragile to reproduce (measured on the real recording, seed 2:
two candidates whose tracking succeeds in 75 % of the episodes cloned to 0 of 20, with 6,000
cloning steps as with 20,000), so the clone is checked (:func:`clone_reproduces`) and, where it
fails, the next shortlisted candidate whose own tracking succeeds at all is cloned instead.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from toolimit.learn.cloning import collect_demonstrations
from toolimit.learn.task import task_from_trajectory
from toolimit.progress import progress_bar
from toolimit.robots import RobotModel
from toolimit.scenes.registry import make_scene
from toolimit.trajopt.selection import SELECTION_JSON, AlignedCandidate, RobotSelection

#: The seed offset of the shortlist's tracking episodes (apart from training, checks and evaluation).
SHORTLIST_SEED = 3000
#: Stage iii's folder of the shortlisted candidates' trajectories.
SHORTLIST_DIR = "shortlist"
#: The field of ``selection.json`` that records the action limit the shortlist was tracked with.
SHORTLIST_ACTION_LIMIT = "shortlist_action_limit"
#: The cloned policy's deterministic success the learner asks before PPO (:func:`clone_reproduces`).
CLONE_ACCEPTED_SUCCESS = 0.5
#: Shortlisted candidates the learner clones at most (then it learns the clone that succeeded most often).
CLONE_ATTEMPTS = 3


@dataclass(frozen=True)
class ShortlistEntry:
    """One shortlisted candidate's trajectory tracked in its learning task.

    Attributes:
        candidate: the candidate's index in the alignment.
        robot_reward: its robot replays' mean goal reward (the selection's ranking).
        horizon: the learning task's episode length, control steps.
        success_rate: fraction of the tracking episodes that met the scene's success test.
        goal_reward_mean: their mean final goal reward.
    """

    candidate: int
    robot_reward: float
    horizon: int
    success_rate: float
    goal_reward_mean: float

    def record(self) -> dict[str, float | int]:
        """A JSON-ready copy."""
        return {
            "candidate": self.candidate,
            "robot_reward": self.robot_reward,
            "horizon": self.horizon,
            "tracking_success_rate": self.success_rate,
            "tracking_goal_reward_mean": self.goal_reward_mean,
        }

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> ShortlistEntry:
        """The entry :meth:`record` wrote."""
        return cls(
            candidate=record["candidate"],
            robot_reward=record["robot_reward"],
            horizon=record["horizon"],
            success_rate=record["tracking_success_rate"],
            goal_reward_mean=record["tracking_goal_reward_mean"],
        )


def shortlist_in_learning_task(
    selection: RobotSelection,
    candidates: list[AlignedCandidate],
    robot: RobotModel,
    tool: str,
    world: str,
    size: int,
    episodes: int,
    seed: int,
    progress: bool = True,
    action_limit: float | None = None,
) -> list[ShortlistEntry]:
    """The ``size`` candidates with the highest robot reward (> 0), best first, each tracked in its
    learning task (built with ``seed`` and ``action_limit``, rad/s, as the learner's) for
    ``episodes`` episodes seeded by :data:`SHORTLIST_SEED` + ``seed``; see the module docstring."""
    rewards = np.nan_to_num(selection.robot_rewards, nan=0.0)
    ranked = sorted((k for k in range(len(candidates)) if rewards[k] > 0), key=lambda k: -rewards[k])[:size]
    scene = make_scene(tool, world)
    entries = []
    for k in progress_bar(ranked, desc="tracking in the learning task", unit="candidate", disable=not progress):
        trajectory = selection.trajectories[k]
        assert trajectory is not None  # a candidate with a robot reward was tracked
        task = task_from_trajectory(
            trajectory, world, candidates[k].params, robot, scene, seed, action_limit=action_limit
        )
        tracked = collect_demonstrations(task, rollouts=episodes, action_noise=0.0, seed=SHORTLIST_SEED + seed)
        entries.append(
            ShortlistEntry(
                candidate=k,
                robot_reward=float(rewards[k]),
                horizon=task.horizon,
                success_rate=float(np.mean(tracked.successes)),
                goal_reward_mean=float(np.mean(tracked.goal_rewards)),
            )
        )
    return entries


def learning_order(entries: list[ShortlistEntry]) -> list[ShortlistEntry]:
    """The entries by how often their tracking succeeds, then by goal reward (then the robot's order)."""
    return sorted(entries, key=lambda entry: (-entry.success_rate, -entry.goal_reward_mean))


def best_to_learn(entries: list[ShortlistEntry]) -> ShortlistEntry:
    """The first of :func:`learning_order`: the candidate the learner starts from."""
    if not entries:
        raise ValueError("an empty shortlist")
    return learning_order(entries)[0]


def shortlist_folder(trajectory_dir: str | os.PathLike[str], candidate: int) -> Path:
    """Where stage iii saves a shortlisted candidate's trajectory (its learner may fall back to it)."""
    return Path(trajectory_dir) / SHORTLIST_DIR / f"candidate_{candidate}"


def shortlist_action_limit(trajectory_dir: str | os.PathLike[str]) -> float | None:
    """The action limit (rad/s; None: the robot's own limits) the shortlist of a trajectory folder's
    ``selection.json`` was tracked with (None also for a folder without a shortlist, and for one
    made before the limit was recorded, when the shortlist always tracked within the robot's limits)."""
    path = Path(trajectory_dir) / SELECTION_JSON
    if not path.is_file():
        return None
    limit = json.loads(path.read_text()).get(SHORTLIST_ACTION_LIMIT)
    return None if limit is None else float(limit)


def read_shortlist(trajectory_dir: str | os.PathLike[str]) -> list[ShortlistEntry]:
    """The shortlist a trajectory folder's ``selection.json`` records, in :func:`learning_order`
    (empty without one: a selection without a shortlist, or a trajectory tracked from poses)."""
    path = Path(trajectory_dir) / SELECTION_JSON
    if not path.is_file():
        return []
    entries = json.loads(path.read_text()).get("shortlist", [])
    return learning_order([ShortlistEntry.from_record(entry) for entry in entries])


def can_fall_back_on(entry: ShortlistEntry) -> bool:
    """Whether the learner may clone this shortlisted candidate when the kept one's clone fails: its
    tracking succeeds at all (an expert that never succeeds gives no clone that does; one that
    succeeds in some episodes may: on the real recording, seed 0, candidate 31's tracking succeeded
    in 95 % and its clone in 0 of 20, candidate 4's in 35 % and its clone in 11 of 20, which PPO took
    to 20 of 20)."""
    return entry.success_rate > 0.0


def clone_reproduces(cloning_record: dict[str, Any]) -> bool:
    """The learner's check of its clone before PPO: its deterministic episodes succeed at least
    :data:`CLONE_ACCEPTED_SUCCESS` of the time (the authors kept a clone whose replay earned any
    reward; measured here, a clone that delivers a sphere where its expert delivers ten or more
    leaves PPO to find the scoop alone)."""
    return float(cloning_record["clone_check"]["success_rate"]) >= CLONE_ACCEPTED_SUCCESS


__all__ = [
    "CLONE_ACCEPTED_SUCCESS",
    "CLONE_ATTEMPTS",
    "SHORTLIST_ACTION_LIMIT",
    "SHORTLIST_SEED",
    "ShortlistEntry",
    "best_to_learn",
    "can_fall_back_on",
    "clone_reproduces",
    "learning_order",
    "read_shortlist",
    "shortlist_action_limit",
    "shortlist_folder",
    "shortlist_in_learning_task",
]
