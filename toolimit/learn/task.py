"""A learning task: what the robot's policy starts from, saved from the pipeline's outputs.

Stage iv needs, from the earlier stages, the scene parameters of the selected alignment candidate
(stage ii) and the robot's optimised joint trajectory with its base (stage iii). A
:class:`LearningTask` holds exactly these, the reference trajectory resampled at the scene's control
rate, and the episode horizon. It is saved as one ``task.npz`` so that an environment can be built
from a fresh install (the shipped tasks of :mod:`toolimit.learn.shipped`) or from a user's own run.

The horizon: the paper's success test asks for the goal to hold for half of the episode (spade: at
least 10 spheres in the box for half of the steps), so an episode as long as the trajectory can
fail although the motion delivers. :func:`success_horizon` replays the reference and holds its last
configuration until the scene reports success, and the task keeps that step count (at most twice
the trajectory). A timed goal (hammer, scythe: the goal within the first second) cannot come later
by holding still: there the horizon is the trajectory's length, as the authors' (``train_ppo.py``:
the cut episode of :mod:`toolimit.align.episode_cut`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from toolimit.align.episode_cut import is_timed
from toolimit.artifacts import load_npz, save_npz
from toolimit.errors import InputError
from toolimit.robots import RobotModel
from toolimit.scenes.base import Scene, SceneParams, pack_scene_params, unpack_scene_params
from toolimit.tools import ToolPose
from toolimit.trajopt.execution import resample_joints
from toolimit.trajopt.result import TrajectoryResult

TASK_NPZ = "task.npz"
_REQUIRED = ("tool", "world", "robot", "joint_names", "reference_q", "base", "horizon", "control_dt", "time_scale")


class TaskFileError(InputError):
    """A task file that is missing or malformed; the message names the file and the problem."""


def action_limit_problem(limit: float | None) -> str | None:
    """Why ``limit`` (rad/s) cannot be a task's action limit, or None when it can (None included)."""
    if limit is None or 0.0 < limit < float("inf"):
        return None
    return f"must be a finite number > 0 (rad/s), got {limit!r}"


@dataclass(frozen=True)
class LearningTask:
    """The start of stage iv: robot, scene and reference motion.

    Attributes:
        tool, world, robot: names for ``make_scene(tool, world)`` and ``make_robot(robot, tool)``.
        joint_names: (N,) the robot's arm joints, in configuration order.
        params: scene parameters of the selected alignment candidate (positions (3,) m, world frame).
        base: (3,) robot base x, y (m) and yaw (rad), world frame.
        reference_q: (T+1, N) optimised joint positions (rad) every ``control_dt`` seconds; the
            tracking controller follows it and an episode starts near reference_q[0].
        horizon: H, control steps of an episode (>= T, see the module docstring).
        control_dt: seconds per control step (the scene's, 1/24 s).
        time_scale: slow-down of the demonstration the trajectory was optimised at (1 = real time).
        source: where the task came from (folders, candidate index), for reports.
        action_limit: every joint's commanded speed is clipped at this many rad/s (the authors'
            environment: 3) instead of the robot's own velocity limits (None); speeds above 0.9 of
            the robot's limits are penalised either way (:mod:`toolimit.learn.simulator`).
    """

    tool: str
    world: str
    robot: str
    joint_names: tuple[str, ...]
    params: dict[str, Any]
    base: np.ndarray
    reference_q: np.ndarray
    horizon: int
    control_dt: float
    time_scale: float
    source: dict[str, str] = field(default_factory=dict)
    action_limit: float | None = None

    def __post_init__(self) -> None:
        if problem := action_limit_problem(self.action_limit):
            raise ValueError(f"action_limit {problem}")

    @property
    def reference_steps(self) -> int:
        """T, the control steps of the reference trajectory."""
        return len(self.reference_q) - 1

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the task as one ``.npz`` (atomically); returns the path."""
        path = Path(path)
        arrays: dict[str, Any] = {
            "tool": np.str_(self.tool),
            "world": np.str_(self.world),
            "robot": np.str_(self.robot),
            "joint_names": np.array(self.joint_names),
            "reference_q": self.reference_q,
            "base": self.base,
            "horizon": np.int64(self.horizon),
            "control_dt": np.float64(self.control_dt),
            "time_scale": np.float64(self.time_scale),
        }
        if self.action_limit is not None:
            arrays["action_limit"] = np.float64(self.action_limit)
        arrays |= pack_scene_params(self.params)
        arrays |= {f"source_{key}": np.str_(value) for key, value in self.source.items()}
        save_npz(path, **arrays)
        return path

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> LearningTask:
        """Read a task written by :meth:`save`; TaskFileError names a missing file, key or bad shape."""
        path = Path(path)
        if path.is_dir():
            path = path / TASK_NPZ
        if not path.is_file():
            raise TaskFileError(f"{path}: no such task file")
        data = load_npz(path, TaskFileError, what="task file", required=_REQUIRED)
        reference_q, base = np.asarray(data["reference_q"], float), np.asarray(data["base"], float)
        joint_names = tuple(str(name) for name in data["joint_names"])
        if reference_q.ndim != 2 or reference_q.shape[1] != len(joint_names) or len(reference_q) < 2:
            raise TaskFileError(f"{path}: reference_q must be (T+1, {len(joint_names)}), got {reference_q.shape}")
        if base.shape != (3,):
            raise TaskFileError(f"{path}: base must be (3,), got {base.shape}")
        horizon = int(data["horizon"])
        if horizon < len(reference_q) - 1:
            raise TaskFileError(
                f"{path}: horizon {horizon} is shorter than the reference ({len(reference_q) - 1} steps)"
            )
        params = unpack_scene_params(data)
        source = {key.removeprefix("source_"): str(value) for key, value in data.items() if key.startswith("source_")}
        try:
            return cls(
                tool=str(data["tool"]),
                world=str(data["world"]),
                robot=str(data["robot"]),
                joint_names=joint_names,
                params=params,
                base=base,
                reference_q=reference_q,
                horizon=horizon,
                control_dt=float(data["control_dt"]),
                time_scale=float(data["time_scale"]),
                source=source,
                action_limit=float(data["action_limit"]) if "action_limit" in data else None,
            )
        except ValueError as invalid:  # __post_init__'s check of a value
            raise TaskFileError(f"{path}: {invalid}") from None


def success_horizon(
    robot: RobotModel,
    scene: Scene,
    params: SceneParams,
    base: np.ndarray,
    reference_q: np.ndarray,
    rng: np.random.Generator,
) -> int:
    """The episode length H in [T, 2T] steps: the reference replayed, then its last configuration
    held, until the scene's success test holds (2T when it never does); T for a timed goal. See
    the module docstring."""
    steps = len(reference_q) - 1
    if is_timed(scene):
        return steps
    held = np.concatenate([reference_q, np.repeat(reference_q[-1:], steps, axis=0)])
    positions, rotations = robot.tool_poses(held[1:], base)
    scene.reset(params, rng)
    for t, (position, rotation) in enumerate(zip(positions, rotations, strict=True), start=1):
        scene.step(ToolPose(position, rotation))
        if t >= steps and bool(scene.is_success()[0]):
            return t
    return 2 * steps


def task_from_trajectory(
    trajectory: TrajectoryResult,
    world: str,
    params: SceneParams,
    robot: RobotModel,
    scene: Scene,
    seed: int = 0,
    source: dict[str, str] | None = None,
    action_limit: float | None = None,
) -> LearningTask:
    """The task of ``trajectory`` (stage iii's result for ``robot``) in ``scene`` with ``params``,
    its actions clipped at ``action_limit`` rad/s (None: the robot's own limits).

    Raises ValueError if the trajectory is another robot's.
    """
    if tuple(trajectory.joint_names) != tuple(robot.joint_names):
        raise ValueError(
            f"the trajectory's joints {list(trajectory.joint_names)} are not robot "
            f"{robot.name}'s {list(robot.joint_names)}"
        )
    reference_q = resample_joints(trajectory.q, trajectory.dt, scene.control_dt)
    horizon = success_horizon(robot, scene, params, trajectory.base, reference_q, np.random.default_rng(seed))
    return LearningTask(
        tool=trajectory.tool,
        world=world,
        robot=robot.name,
        joint_names=tuple(robot.joint_names),
        params=unpack_scene_params(pack_scene_params(params)),
        base=np.asarray(trajectory.base, dtype=float),
        reference_q=reference_q,
        horizon=horizon,
        control_dt=scene.control_dt,
        time_scale=trajectory.time_scale,
        source=dict(source or {}),
        action_limit=action_limit,
    )


def task_from_pipeline(
    alignment_dir: str | os.PathLike[str], trajectory_dir: str | os.PathLike[str], seed: int = 0
) -> LearningTask:
    """The task of a finished pipeline: stage iii's trajectory in the scene it was tracked in.

    The scene is the alignment candidate the trajectory records (``TrajectoryResult.scene``), read
    back from ``alignment_dir`` and checked against it. TaskFileError names a missing file, a
    trajectory that records no scene (tracked from poses alone), another tool, or a trajectory
    tracked in another alignment (its candidate's scene parameters differ from ``alignment_dir``'s).
    """
    from toolimit.robots import make_robot
    from toolimit.scenes.registry import make_scene
    from toolimit.trajopt.selection import load_candidates

    alignment_dir, trajectory_dir = Path(alignment_dir), Path(trajectory_dir)
    try:
        trajectory = TrajectoryResult.load(trajectory_dir)
        tool, world, candidates = load_candidates(alignment_dir)
    except (OSError, ValueError, KeyError) as error:
        raise TaskFileError(str(error)) from None
    scene = trajectory.scene
    if scene is None:
        raise TaskFileError(
            f"{trajectory_dir}: the trajectory records no scene (it was tracked from poses, not from an "
            "alignment's candidates): track it with `toolimit trajopt --alignment DIR`"
        )
    if tool != trajectory.tool:
        raise TaskFileError(
            f"{trajectory_dir}: the trajectory is for the {trajectory.tool}, "
            f"the alignment in {alignment_dir} for the {tool}"
        )
    k = scene.candidate
    if world != scene.world or k >= len(candidates) or not _same_params(candidates[k].params, scene.params):
        raise TaskFileError(
            f"{trajectory_dir}: the trajectory was tracked in candidate {k} of another alignment than "
            f"{alignment_dir} (its scene parameters differ): pair it with the alignment it was tracked from"
        )
    robot = make_robot(trajectory.robot, tool=tool)
    source = {"alignment": str(alignment_dir), "trajectory": str(trajectory_dir), "candidate": str(k)}
    return task_from_trajectory(trajectory, world, scene.params, robot, make_scene(tool, world), seed, source)


def _same_params(first: SceneParams, second: SceneParams) -> bool:
    """Same parameter names and values (to float rounding)."""
    return first.keys() == second.keys() and all(np.allclose(first[name], second[name]) for name in first)
