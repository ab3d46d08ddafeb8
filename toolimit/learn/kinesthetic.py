"""The LfD baseline's kinesthetic demonstration: a scripted tool motion tracked by the robot.

The paper compares its method with learning from a kinesthetic demonstration: a joint trajectory
that solves the task in the robot's own scene without the video (a person guiding the arm), cloned
then fine-tuned by PPO. Here the scene is the method's learning task's (the scene parameters of
its selected alignment candidate), the motion is the scene's hand-made one
(:func:`toolimit.scenes.registry.scripted_motion`: a scoop, a strike, a sweep) and the robot follows
it with stage iii: :func:`toolimit.trajopt.selection.select_by_robot_execution` with the scripted
motion as its only candidate, i.e. the same tracking, base placement outside the scene's elements,
time-scale choice by robot replay and replays as the pipeline's.

A kinesthetic demonstration solves the task on the robot: a person guiding the arm goes as slowly
as the arm needs. So when the robot's replay at the pipeline's time scales earns nothing, the
motion is tracked again at each slower scale of stage iii's grid
(:data:`~toolimit.trajopt.time_scale.TIME_SCALE_GRID`) in turn, and the first whose replay earns
is kept (the Panda, within its acceleration limits, cannot follow the hammer's 2 m/s strikes at
real time; ``selection.json`` lists the reward of every pace tried). When no pace earns, there is
no demonstration: NoKinestheticDemonstration. The result is a
:class:`~toolimit.learn.task.LearningTask` in the same scene, learnt from exactly as the method's;
its ``source`` names the demonstration's folder (``kinesthetic``) and, prefixed ``scene_``, where
the scene parameters came from (the method task's own ``source``).

A demonstration folder holds ``trajectory.npz`` / ``trajectory.json`` (stage iii's format),
``selection.json`` (the scripted motion's tool-only reward, the robot's replay reward at every time
scale tried) and ``task.npz``, written last: a folder with it is finished and is read back, not redone.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from toolimit.artifacts import save_json
from toolimit.errors import BaseInsideFootprint, NoKinestheticDemonstration
from toolimit.learn.task import TASK_NPZ, LearningTask, task_from_trajectory
from toolimit.robots import RobotModel, make_robot
from toolimit.scenes.registry import make_scene, scripted_motion
from toolimit.scenes.replay import replay
from toolimit.trajopt.problem import PoseTargets
from toolimit.trajopt.selection import (
    SELECTION_JSON,
    AlignedCandidate,
    RobotSelection,
    select_by_robot_execution,
)
from toolimit.trajopt.time_scale import TIME_SCALE_GRID
from toolimit.trajopt.track import TrackOptions


def kinesthetic_task(
    task: LearningTask,
    folder: Path,
    options: TrackOptions,
    time_scales: tuple[float, ...],
    seed: int = 0,
    replays: int = 10,
) -> LearningTask:
    """The LfD task for ``task``'s robot, tool and scene parameters, saved in ``folder`` (module
    docstring), or read from there when finished earlier.

    ``options`` (weights, starts) and ``time_scales`` are stage iii's; ``seed`` seeds the replays,
    the tracking's random starts and the horizon's replay. Raises BaseInsideFootprint when every
    solution puts the robot's base inside a scene element, NoKinestheticDemonstration when the
    robot's replay earns nothing at any pace, SolverFailure when OSQP gives up, NoScriptedMotion for
    a scene without a hand-made motion; nothing is written then.
    """
    if (folder / TASK_NPZ).is_file():
        return LearningTask.load(folder / TASK_NPZ)
    scene = make_scene(task.tool, task.world)
    motion = scripted_motion(task.tool, task.world, task.params, fps=1.0 / scene.control_dt)
    # a kinesthetic demonstration is the robot's own motion, the targets it tracks: replayed as given
    # (the tool speed limit is the alignment's tool-alone replay, toolimit.scenes.replay)
    tool_rewards = replay(scene, task.params, np.random.default_rng(seed), motion, batch_size=replays, tool_alone=False)
    candidate = AlignedCandidate(
        PoseTargets(motion.position, motion.rotation, 1.0 / scene.control_dt), task.params, float(tool_rewards.mean())
    )
    robot = make_robot(task.robot, tool=task.tool)
    selection = _robot_demonstration(robot, candidate, task.tool, task.world, options, time_scales, seed, replays)
    trajectory = selection.trajectories[0]
    assert trajectory is not None  # a selection whose replay earned has its trajectory
    trajectory.save(folder)
    save_json(folder / SELECTION_JSON, selection.record([candidate]))
    source = {"kinesthetic": str(folder)} | {f"scene_{key}": value for key, value in task.source.items()}
    lfd_task = task_from_trajectory(trajectory, task.world, task.params, robot, scene, seed, source)
    lfd_task.save(folder / TASK_NPZ)
    return lfd_task


def _robot_demonstration(
    robot: RobotModel,
    candidate: AlignedCandidate,
    tool: str,
    world: str,
    options: TrackOptions,
    time_scales: tuple[float, ...],
    seed: int,
    replays: int,
) -> RobotSelection:
    """The robot's selection at ``time_scales``, or else at the first slower scale of
    ``TIME_SCALE_GRID`` whose replay earns (module docstring); its record lists the reward at every
    time scale tried."""
    tried: dict[float, float] = {}
    paces = [tuple(time_scales)] + [(scale,) for scale in TIME_SCALE_GRID if scale > max(time_scales)]
    for scales in paces:
        selection = select_by_robot_execution(
            robot,
            [candidate],
            tool,
            world,
            replace(options, progress=False),
            seed=seed,
            replays=replays,
            progress=False,
            time_scales=scales,
        )
        tried |= selection.time_scale_rewards[0]
        if selection.best is not None:
            return replace(selection, time_scale_rewards=[tried])
    if all(np.isnan(reward) for reward in tried.values()):
        raise BaseInsideFootprint(f"the {robot.name} cannot track the scripted {tool} motion: {selection.refusals[0]}")
    paces_tried = ", ".join(f"{scale:g}" for scale in tried)
    raise NoKinestheticDemonstration(
        f"the {robot.name} tracking the scripted {tool} motion earns nothing at time scales {paces_tried}: "
        "no kinesthetic demonstration"
    )
