"""meshcat animation of one episode of a learned policy: the robot, its tool and the 3D scene.

Stage iv's evaluation rolls a policy out in the task's simulator (:mod:`toolimit.learn.simulator`).
:func:`record_rollout` runs one such episode and keeps what a view needs: the joint positions and
the scene's ``snapshot()`` at every control step (the sand, the boxes, as they actually moved in
that episode; not a replay, which would draw the scene's randomness again). :func:`rollout_html`
draws it as one self-contained HTML page with the view of :mod:`toolimit.viz.meshcat_robot`: the
robot at the task's base, the tool at its tool frame with the reached path, and the world's
elements (:mod:`toolimit.viz.world_elements`, 3D worlds only) animated from the snapshots, played
at the control rate (24 Hz; the task's time scale is already in its trajectory).

Frames: world, metres, z up; joints in radians.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from toolimit.learn.evaluate import EVALUATION_SEED
from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.task import LearningTask
from toolimit.robots import make_robot
from toolimit.viz.meshcat_robot import _animated_view
from toolimit.viz.meshcat_views import save_html


class Policy(Protocol):
    """What acts in a rollout: stable-baselines3's ``predict`` (PPO, a loaded policy.safetensors)."""

    def predict(self, observation: np.ndarray, deterministic: bool = ...) -> tuple[np.ndarray, Any]: ...


@dataclass(frozen=True)
class Rollout:
    """One episode of a task.

    Attributes:
        q: (H+1, N) joint positions, rad; q[0] after the reset, q[t] after step t.
        snapshots: H+1 scene snapshots (instance 0) taken at the same instants as ``q``.
        goal_rewards: (H,) the scene's goal reward after each step (spade: grains in the box).
        success: the paper's criterion over the episode.
    """

    q: np.ndarray
    snapshots: list[dict[str, np.ndarray]]
    goal_rewards: np.ndarray
    success: bool


def record_rollout(
    task: LearningTask,
    policy: Policy | None = None,
    deterministic: bool = True,
    seed: int = EVALUATION_SEED,
    scene_kwargs: dict[str, Any] | None = None,
) -> Rollout:
    """Run one episode of ``task`` with ``policy`` (its mean if ``deterministic``), or with the
    tracking controller (the cloning expert) when ``policy`` is None; reset with ``seed``."""
    simulator = TaskSimulator(task, batch_size=1, scene_kwargs=scene_kwargs)
    observation = simulator.reset(np.random.default_rng(seed))
    q, snapshots, goals = [simulator.q[0].copy()], [simulator.scene.snapshot()], []
    while not simulator.done:
        if policy is None:
            action = simulator.tracking_action()
        else:
            action, _ = policy.predict(observation, deterministic=deterministic)
        observation, _, goal = simulator.step(action)
        q.append(simulator.q[0].copy())
        snapshots.append(simulator.scene.snapshot())
        goals.append(float(goal[0]))
    return Rollout(np.array(q), snapshots, np.array(goals), bool(simulator.is_success()[0]))


def rollout_html(path: str | os.PathLike[str], task: LearningTask, rollout: Rollout, stride: int = 1) -> Path:
    """Write ``rollout`` of ``task`` as one self-contained HTML animation (atomically); returns the path.

    ``stride`` keeps every stride-th control step (and the last), for a smaller page; the animation
    still plays in real time. Planar worlds have no 3D view of their elements: the robot and the
    tool are drawn over a plain ground. Raises ValueError for a rollout of another robot or a bad
    stride.
    """
    robot = make_robot(task.robot, tool=task.tool)
    q = np.asarray(rollout.q, dtype=float)
    if q.ndim != 2 or q.shape[1] != robot.n_joints or len(q) != len(rollout.snapshots):
        raise ValueError(
            f"rollout q must be (H+1, {robot.n_joints}) with one snapshot per row for {task.robot}, "
            f"got {q.shape} and {len(rollout.snapshots)} snapshots"
        )
    if int(stride) != stride or stride < 1:
        raise ValueError(f"stride must be an integer >= 1, got {stride!r}")
    kept = np.unique(np.r_[np.arange(0, len(q), int(stride)), len(q) - 1])
    frames = [rollout.snapshots[i] for i in kept] if task.world == "3d" else None
    frame_dt = task.control_dt * int(stride)
    visualizer = _animated_view(robot, q[kept], task.base, frame_dt, world_frames=frames)
    return save_html(visualizer, path)
