"""Measuring each method of an experiment on the same footing (see :mod:`toolimit.experiments.cells`).

Each function rolls ``episodes`` instances out at once from one seeded generator and returns a
:class:`CellResult`. They read what ``toolimit run`` and ``toolimit learn`` wrote: the learning task
(``learning/task.npz``: scene parameters of the selected candidate, trajectory, horizon H), the
alignment's candidates and the learnt policies.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from toolimit.align.outputs import CANDIDATES_NPZ
from toolimit.deploy.export import plan_export
from toolimit.deploy.open_loop import replay_open_loop
from toolimit.errors import InputError
from toolimit.experiments.cells import CellResult, Experiment
from toolimit.learn.cloning import collect_demonstrations
from toolimit.learn.evaluate import evaluate
from toolimit.learn.task import LearningTask
from toolimit.learn.training import LEARNING_JSON, load_policy
from toolimit.robots.limits import SUPPORTED_ROBOTS, Margins, published_limits
from toolimit.scenes.registry import make_scene
from toolimit.scenes.replay import replay
from toolimit.tools import ToolPose, hold_last
from toolimit.trajopt.result import JointTrajectory
from toolimit.trajopt.selection import load_candidates


def measure_tool_only(experiment: Experiment, task: LearningTask, episodes: int, seed: int) -> CellResult:
    """The selected candidate's tool motion alone in its scene, at the demonstration's speed, then
    held at its last pose until the task's horizon H (stage ii's result)."""
    source = task.source
    if not source.get("candidate", "").isdigit():
        raise InputError(
            f"the task of {experiment.name} names no selected candidate ({source}): make it with "
            "`toolimit trajopt --select-by-robot`"
        )
    _, _, candidates = load_candidates(Path(source["alignment"]) / CANDIDATES_NPZ)
    targets = candidates[int(source["candidate"])].targets
    if not np.isclose(targets.fps * task.control_dt, 1.0):
        raise InputError(
            f"{experiment.name}: the aligned motion has {targets.fps} fps, the scene steps at {1 / task.control_dt:g}"
        )
    poses = hold_last(ToolPose(targets.positions, targets.rotations), max(task.horizon - len(targets.positions), 0))
    scene = make_scene(task.tool, task.world)
    rng = np.random.default_rng(seed)
    goal = replay(scene, task.params, rng, poses, batch_size=episodes)
    return CellResult.of(experiment, "tool_only", goal, np.asarray(scene.is_success(), dtype=bool))


def measure_trajopt(experiment: Experiment, task: LearningTask, episodes: int, seed: int) -> CellResult:
    """The robot's optimised trajectory executed by the tracking controller in the learning task
    (the task's reset noise, horizon H; stage iii's result, the cloning's expert)."""
    rollouts = collect_demonstrations(task, rollouts=episodes, action_noise=0.0, seed=seed)
    return CellResult.of(experiment, "trajopt", rollouts.goal_rewards, rollouts.successes)


def measure_policy(experiment: Experiment, method: str, policy_dir: Path, episodes: int, seed: int) -> CellResult:
    """A learnt policy's deterministic rollouts (``toolimit learn``'s folder ``policy_dir``), how far
    they go past the robot's limits, and for the final policy on a robot with published limits its
    first rollout exported and replayed open-loop from the same resets; env steps and wall time
    from its ``learning.json``."""
    model, task = load_policy(policy_dir)
    evaluation = evaluate(model, task, episodes, deterministic=True, seed=seed)
    learned = json.loads((policy_dir / LEARNING_JSON).read_text())
    exported = None
    if method == "final" and task.robot in SUPPORTED_ROBOTS:
        q = evaluation.joint_positions[0]
        rollout = JointTrajectory(q, np.diff(q, axis=0) / task.control_dt, task.base, task.joint_names, task.control_dt)
        plan = plan_export(rollout, published_limits(task.robot).within(Margins()))
        exported = replay_open_loop(plan.samples.times, plan.samples.position, task, episodes, seed).record()
    return CellResult.of(
        experiment,
        method,
        evaluation.goal_rewards,
        evaluation.successes,
        env_steps=learned["env_steps"],
        wall_time_s=learned["wall_time_s"],
        limits=evaluation.limits.record(),
        exported=exported,
    )
