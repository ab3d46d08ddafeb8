"""Choosing among the alignment's candidates by robot execution (the paper's last step of stage ii).

Alignment keeps the first K scene samples whose *tool-only* replay earns a goal reward. A robot
may not reproduce every one of them: its reach, velocity limits or the way it holds the tool can
rule a candidate out. So each candidate is tracked by the robot, the robot's joint trajectory is
replayed in the candidate's scene, and the candidate whose robot replay earns the most goal reward
wins (ties: the lower tracking cost J).

The time scale is chosen the same way when several are given: each candidate is tracked at every
scale and keeps the one whose robot replay earns the most (ties: the lower median position error).
Tracking accuracy alone is the wrong criterion for a task whose reward depends on the motion's
speed. Measured on the 3D spade (Panda, ``--velocity-weight 1e-4``, 10 replays): the authors'
``spade_video1_aligned`` in its own scene earns 9.3 spheres at real time (median error 6.1 cm: the
robot lags at its velocity limits) and 6.0-7.5 at scales 1.5-5 (4.5-0.1 cm), where the tool alone
also earns less (8.2 at real time, 3.2 at scale 5: a slowed throw falls short of the box); of the
20 candidates of ``spade_00`` (seed 0), 5 keep real time (among them the best: 9.7 spheres, 4.6 at
scale 1.5), 10 keep 1.5 and 4 keep 2. The replay's reward says nothing of what a policy can learn
from the trajectory: a slowed one doubles the episode, in which PPO's exploration noise loses the
sand, so the pipeline selects at real time (measurements at
:class:`toolimit.pipeline.settings.TrajoptSettings`, ``time_scales``).
"""

from __future__ import annotations

import contextlib
import os
import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from toolimit.artifacts import load_npz
from toolimit.distributed import RayTarget, ray_cluster
from toolimit.errors import BaseInsideFootprint, InputError
from toolimit.progress import progress_bar
from toolimit.robots.model import RobotModel
from toolimit.scenes.base import SceneParams, unpack_scene_params
from toolimit.scenes.registry import make_scene
from toolimit.trajopt.execution import execute_in_scene
from toolimit.trajopt.problem import PoseTargets
from toolimit.trajopt.result import TrackedScene, TrajectoryResult, UpsideDownTracking
from toolimit.trajopt.track import TrackOptions, track
from toolimit.workers import ordered_results

#: The robot's selection record (``RobotSelection.record``) beside the kept trajectory.
SELECTION_JSON = "selection.json"


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
        time_scale_rewards: per candidate, the robot reward at each time scale tried (NaN where refused).
    """

    best: int | None
    trajectories: list[TrajectoryResult | None]
    robot_rewards: np.ndarray
    refusals: list[str | None]
    time_scale_rewards: list[dict[float, float]]

    def record(self, candidates: list[AlignedCandidate]) -> dict:
        """A JSON-ready summary, one entry per candidate."""
        return {
            "best": self.best,
            "candidates": [
                {
                    "alignment_reward": candidate.alignment_reward,
                    "robot_reward": None if np.isnan(reward) else float(reward),
                    "cost": None if trajectory is None else trajectory.cost,
                    "time_scale": None if trajectory is None else trajectory.time_scale,
                    "median_position_error_m": None
                    if trajectory is None
                    else float(np.median(trajectory.position_error)),
                    "median_rotation_error_rad": None
                    if trajectory is None
                    else float(np.median(trajectory.rotation_error)),
                    "upside_down": None if trajectory is None else trajectory.upside_down,
                    "refused": refusal,
                    "robot_reward_by_time_scale": {
                        f"{scale:g}": None if np.isnan(value) else value for scale, value in by_scale.items()
                    },
                }
                for candidate, trajectory, reward, refusal, by_scale in zip(
                    candidates, self.trajectories, self.robot_rewards, self.refusals, self.time_scale_rewards
                )
            ],
        }


def load_candidates(path: str | os.PathLike[str]) -> tuple[str, str, list[AlignedCandidate]]:
    """(tool, world, candidates) from an alignment's ``candidates.npz`` (``path``, or the alignment
    folder holding it): the one reader of that file."""
    from toolimit.align.outputs import CANDIDATES_NPZ

    path = Path(path)
    if path.is_dir():
        path = path / CANDIDATES_NPZ
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file (run `toolimit align` first)")
    arrays = load_npz(
        path, required=("tip_position", "tip_quaternion_wxyz", "fps", "tool", "scene_world", "alignment_reward")
    )
    positions, quaternions = arrays["tip_position"], arrays["tip_quaternion_wxyz"]
    fps = float(arrays["fps"])
    rewards = arrays["alignment_reward"]
    params = unpack_scene_params(arrays)
    tool, world = str(arrays["tool"]), str(arrays["scene_world"])
    # Each candidate's episode length (a timed goal's cut episodes differ; older files: all frames).
    frames = np.asarray(arrays.get("episode_frames", np.full(len(positions), positions.shape[1])), dtype=int)
    if positions.ndim != 3 or positions.shape[2] != 3 or quaternions.shape[:2] != positions.shape[:2]:
        raise InputError(
            f"{path}: tip_position must be (K, T, 3) and tip_quaternion_wxyz (K, T, 4), "
            f"got {positions.shape} and {quaternions.shape}"
        )
    candidates = [
        AlignedCandidate(
            targets=PoseTargets.from_quaternions(positions[k, : frames[k]], quaternions[k, : frames[k]], fps),
            params={name: _row(value, k) for name, value in params.items()},
            alignment_reward=float(rewards[k]),
        )
        for k in range(len(positions))
    ]
    return tool, world, candidates


def _row(stacked: np.ndarray | float, k: int) -> np.ndarray | float:
    """Candidate k's value of a parameter stacked over the candidates (a float when 0-d)."""
    value = np.asarray(stacked)[k]
    return value if value.ndim else float(value)


def select_by_robot_execution(
    robot: RobotModel,
    candidates: list[AlignedCandidate],
    tool: str,
    world: str,
    options: TrackOptions,
    seed: int = 0,
    replays: int = 10,
    progress: bool = True,
    time_scales: tuple[float, ...] | None = None,
    workers: int = 1,
    ray: RayTarget = False,
) -> RobotSelection:
    """Track every candidate (:func:`~toolimit.trajopt.track.track`), replay the robot in its scene
    ``replays`` times and pick the candidate with the highest mean robot reward.

    ``time_scales``: the slow-down factors to track each candidate at (the module docstring says
    how one is kept); None tracks at ``options.time_scale`` only. Candidate k's tracking and
    replays draw from ``default_rng([seed, k])``, its scales in ascending order; its base guesses
    avoid the scene's element footprints. ``workers`` processes track candidates side by side
    (:mod:`toolimit.workers`), or with ``ray`` one actor per CPU of a Ray cluster
    (:data:`~toolimit.distributed.RayTarget`); the selection does not depend on it. Each kept trajectory
    records its candidate (``TrajectoryResult.scene``); an upside-down tracking is warned
    (:class:`~toolimit.trajopt.result.UpsideDownTracking`) for the selected candidate only.
    """
    if not candidates:
        raise InputError("no alignment candidate to select from")
    if not (isinstance(workers, int) and workers >= 1):
        raise InputError(f"workers: expected a positive integer, got {workers!r}")
    scales = tuple(sorted(time_scales) if time_scales is not None else [options.time_scale])
    if not scales:
        raise InputError("the time-scale grid is empty")
    trajectories: list[TrajectoryResult | None] = []
    rewards: list[float] = []
    refusals: list[str | None] = []
    by_scale: list[dict[float, float]] = []
    arguments = (
        (robot, candidate, k, tool, world, options, seed, replays, scales) for k, candidate in enumerate(candidates)
    )
    with ray_cluster(ray) if ray else contextlib.nullcontext() as cluster:
        where = "" if cluster is None else f" on {cluster.summary()}"
        bar = progress_bar(
            total=len(candidates), desc=f"robot execution{where}", unit="candidate", disable=not progress
        )
        with bar:
            for kept, refusal, rewards_by_scale in ordered_results(
                _execute_candidate, arguments, workers, on_ray=cluster is not None
            ):
                trajectories.append(None if kept is None else kept[1])
                rewards.append(float("nan") if kept is None else kept[0])
                refusals.append(refusal if kept is None else None)
                by_scale.append(rewards_by_scale)
                bar.update()
    robot_rewards = np.array(rewards)
    ranked = [k for k in range(len(candidates)) if robot_rewards[k] > 0]
    costs = [float("nan") if trajectory is None else trajectory.cost for trajectory in trajectories]
    best = min(ranked, key=lambda k: (-robot_rewards[k], costs[k]), default=None)
    chosen = None if best is None else trajectories[best]
    if chosen is not None and chosen.upside_down:
        warnings.warn(UpsideDownTracking.of(chosen), stacklevel=2)
    return RobotSelection(best, trajectories, robot_rewards, refusals, by_scale)


def _execute_candidate(
    robot: RobotModel,
    candidate: AlignedCandidate,
    k: int,
    tool: str,
    world: str,
    options: TrackOptions,
    seed: int,
    replays: int,
    scales: tuple[float, ...],
) -> tuple[tuple[float, TrajectoryResult] | None, str | None, dict[float, float]]:
    """Candidate k tracked and replayed at every scale: the kept (robot reward, trajectory) (None
    when every scale was refused), the last refusal, and the robot reward per scale (NaN: refused)."""
    scene = make_scene(tool, world)
    rng = np.random.default_rng([seed, k])
    candidate_options = replace(options, footprints=scene.footprints(candidate.params))
    kept: tuple[float, TrajectoryResult] | None = None
    refusal: str | None = None
    by_scale: dict[float, float] = {}
    scene_record = TrackedScene(world, k, candidate.params)
    for scale in scales:
        try:  # refused where every base the solver finds, or the one it keeps, stands in an element
            with warnings.catch_warnings():  # only the selected candidate's is worth a warning
                warnings.simplefilter("ignore", UpsideDownTracking)
                tracked = track(robot, candidate.targets, replace(candidate_options, time_scale=float(scale)), rng=rng)
            trajectory = replace(tracked, scene=scene_record)
            reward = float(np.mean(execute_in_scene(robot, trajectory, scene, candidate.params, rng, replays)))
        except BaseInsideFootprint as error:
            by_scale[float(scale)] = float("nan")
            refusal = str(error)
            continue
        by_scale[float(scale)] = reward
        if kept is None or (reward, -np.median(trajectory.position_error)) > (
            kept[0],
            -np.median(kept[1].position_error),
        ):
            kept = (reward, trajectory)
    return kept, refusal, by_scale
