"""Choosing among the alignment's candidates by robot execution (the paper's last step of stage ii).

Alignment keeps the first K scene samples whose *tool-only* replay earns a goal reward. A robot
may not reproduce every one of them: its reach, velocity limits or the way it holds the tool can
rule a candidate out. So each candidate is tracked by the robot, the robot's joint trajectory is
replayed in the candidate's scene, and the candidate whose robot replay earns the most goal reward
wins (ties: the lower tracking cost J).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from toolimit.errors import BaseInsideFootprint, InputError
from toolimit.progress import tqdm
from toolimit.robots.model import RobotModel
from toolimit.scenes.base import SceneParams
from toolimit.scenes.registry import make_scene
from toolimit.trajopt.execution import execute_in_scene
from toolimit.trajopt.problem import PoseTargets
from toolimit.trajopt.result import TrajectoryResult
from toolimit.trajopt.track import TrackOptions

#: A tracking solver: robot, targets, options (with the scene's footprints), rng -> result.
Solver = Callable[[RobotModel, PoseTargets, TrackOptions, np.random.Generator], TrajectoryResult]


@dataclass(frozen=True)
class AlignedCandidate:
    """One alignment candidate: the tool motion to track and the scene it was aligned in.

    Attributes:
        targets: tool-frame poses over time, world frame.
        params: the scene parameters (position parameters (3,) m, uniform ones floats).
        alignment_reward: mean goal reward of the tool-only replays.
    """

    targets: PoseTargets
    params: SceneParams
    alignment_reward: float


@dataclass
class RobotSelection:
    """Outcome of :func:`select_by_robot_execution`.

    Attributes:
        best: index of the chosen candidate, or None when no robot replay earned a reward.
        trajectories: per candidate, the robot's tracking result (None where refused).
        robot_rewards: (K,) mean goal reward of the robot replays (NaN where the replay was refused).
        refusals: per candidate, why it was refused (the robot's base inside a scene element), or None.
    """

    best: int | None
    trajectories: list[TrajectoryResult | None]
    robot_rewards: np.ndarray
    refusals: list[str | None]

    def record(self, candidates: list[AlignedCandidate]) -> dict:
        """A JSON-ready summary, one entry per candidate."""
        return {
            "best": self.best,
            "candidates": [
                {
                    "alignment_reward": candidate.alignment_reward,
                    "robot_reward": None if np.isnan(reward) else float(reward),
                    "cost": None if trajectory is None else trajectory.statistics["cost"],
                    "time_scale": None if trajectory is None else trajectory.time_scale,
                    "median_position_error_m": None if trajectory is None else float(np.median(trajectory.position_error)),
                    "median_rotation_error_rad": None if trajectory is None else float(np.median(trajectory.rotation_error)),
                    "upside_down": None if trajectory is None else trajectory.upside_down,
                    "refused": refusal,
                }
                for candidate, trajectory, reward, refusal in zip(
                    candidates, self.trajectories, self.robot_rewards, self.refusals
                )
            ],
        }


def load_candidates(path: str | os.PathLike[str]) -> tuple[str, str, list[AlignedCandidate]]:
    """(tool, world, candidates) from an alignment's ``candidates.npz``."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file (run `toolimit align` first)")
    with np.load(path) as arrays:
        missing = [k for k in ("tip_position", "tip_quaternion_wxyz", "fps", "tool", "scene_world",
                               "alignment_reward") if k not in arrays.files]
        if missing:
            raise InputError(f"{path}: missing keys {missing}")
        positions, quaternions = arrays["tip_position"], arrays["tip_quaternion_wxyz"]
        fps = float(arrays["fps"])
        rewards = arrays["alignment_reward"]
        params = {k.removeprefix("param_"): arrays[k] for k in arrays.files if k.startswith("param_")}
        tool, world = str(arrays["tool"]), str(arrays["scene_world"])
    if positions.ndim != 3 or positions.shape[2] != 3 or quaternions.shape[:2] != positions.shape[:2]:
        raise InputError(f"{path}: tip_position must be (K, T, 3) and tip_quaternion_wxyz (K, T, 4), "
                         f"got {positions.shape} and {quaternions.shape}")
    candidates = [
        AlignedCandidate(
            targets=PoseTargets.from_quaternions(positions[k], quaternions[k], fps),
            params={name: value[k] if value[k].ndim else float(value[k]) for name, value in params.items()},
            alignment_reward=float(rewards[k]),
        )
        for k in range(len(positions))
    ]
    return tool, world, candidates


def select_by_robot_execution(
    robot: RobotModel,
    candidates: list[AlignedCandidate],
    tool: str,
    world: str,
    options: TrackOptions,
    solve: Solver,
    seed: int = 0,
    replays: int = 10,
    progress: bool = True,
) -> RobotSelection:
    """Track every candidate with ``solve``, replay the robot in its scene ``replays`` times and
    pick the candidate with the highest mean robot reward.

    Candidate k's tracking and replays draw from ``default_rng([seed, k])``; its base guesses avoid
    the scene's element footprints.
    """
    if not candidates:
        raise InputError("no alignment candidate to select from")
    scene = make_scene(tool, world)
    trajectories, rewards, refusals = [], [], []
    for k, candidate in enumerate(tqdm(candidates, desc="robot execution", unit="candidate", disable=not progress)):
        rng = np.random.default_rng([seed, k])
        candidate_options = replace(options, footprints=scene.footprints(candidate.params))
        try:  # refused where every base the solver finds, or the one it keeps, stands in an element
            trajectory = solve(robot, candidate.targets, candidate_options, rng)
            reward = float(np.mean(execute_in_scene(robot, trajectory, scene, candidate.params, rng, replays)))
            refusal = None
        except BaseInsideFootprint as error:
            reward, refusal = float("nan"), str(error)
            trajectory = None
        trajectories.append(trajectory)
        rewards.append(reward)
        refusals.append(refusal)
    robot_rewards = np.array(rewards)
    ranked = [k for k in range(len(candidates)) if robot_rewards[k] > 0]
    costs = [float("nan") if trajectory is None else trajectory.statistics["cost"] for trajectory in trajectories]
    best = min(ranked, key=lambda k: (-robot_rewards[k], costs[k]), default=None)
    return RobotSelection(best, trajectories, robot_rewards, refusals)
