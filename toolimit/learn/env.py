"""The Gymnasium environment of one robot, its tool and a scene: ``gymnasium.make("toolimit/Spade3D-v0")``.

Observation, action and reward are those of :mod:`toolimit.learn.simulator`. An episode lasts the
task's horizon H and ends with ``truncated=True`` (``terminated`` is never set: nothing ends the
task early). ``info`` holds ``goal_reward`` (the scene's goal reward after the step) and, at the
last step, ``is_success`` (the paper's criterion over the episode).

Registered ids (:func:`register_environments`, run on ``import toolimit.learn``; call it again
after registering a tool): ``toolimit/<Tool><World>-v0`` for every registered tool with a scene and
a default robot in that world (:func:`toolimit.learn.shipped.environments`): Spade, Hammer, Scythe x
3D, Planar for the built-in tools. Each starts from a shipped task (:mod:`toolimit.learn.shipped`):
the Panda in 3D, the planar 3-link arm in the plane.
Keywords: ``task=`` a :class:`LearningTask` or a task file of your own run (``toolimit learn``
makes one), ``robot=`` another robot's shipped task, ``scene_kwargs=`` the scene's constructor,
``reward="dense"`` the dense-reward baseline's reward, ``adr=True`` the goal box drawn at every
reset inside the ADR bounds and observed (spades; :mod:`toolimit.learn.adr`; the bounds stay at the
aligned position unless something moves them, as ``toolimit learn --adr`` does).
"""

from __future__ import annotations

import os
from typing import Any

import gymnasium as gym
import numpy as np

from toolimit.learn.adr import BOX_OFFSET_UNIT
from toolimit.learn.shipped import environments, shipped_task
from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.task import LearningTask
from toolimit.live_names import LiveNames
from toolimit.scenes.base import WORLD_HALF_SIZE

#: The id's spelling of each world.
ENV_WORLDS = {"3d": "3D", "planar": "Planar"}
#: The tools with a registered id in some world (a live view of the tool registry).
ENV_TOOLS = LiveNames("ENV_TOOLS", lambda: tuple(dict.fromkeys(tool for tool, _ in environments())))


def env_id(tool: str, world: str) -> str:
    """The registered id, e.g. ``env_id("spade", "3d") == "toolimit/Spade3D-v0"``."""
    return f"toolimit/{tool.capitalize()}{ENV_WORLDS[world]}-v0"


#: Bound of the tool position's coordinates in the observation space, m (far beyond any reach).
TOOL_POSITION_BOUND = 10.0
#: Bound of the observed goal box offset under ADR, in its units: any box in the world, from any
#: aligned position in it. An ADR policy whose space has another bound observed the box otherwise.
BOX_OFFSET_BOUND = 2 * WORLD_HALF_SIZE / BOX_OFFSET_UNIT


def observation_space(simulator: TaskSimulator) -> gym.spaces.Box:
    """float32 box: tool position within +-TOOL_POSITION_BOUND m, quaternion in [-1, 1], joints
    within their limits (rad), elapsed time in [0, H dt] s (, goal box offset x, y within
    +-BOX_OFFSET_BOUND units of 0.1 m under ADR)."""
    robot = simulator.robot
    box = np.full(2 * simulator.adr, BOX_OFFSET_BOUND)
    low = np.concatenate([np.full(3, -TOOL_POSITION_BOUND), -np.ones(4), robot.lower, [0.0], -box])
    high = np.concatenate(
        [np.full(3, TOOL_POSITION_BOUND), np.ones(4), robot.upper, [simulator.horizon * simulator.dt], box]
    )
    return gym.spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)


def action_space(simulator: TaskSimulator) -> gym.spaces.Box:
    """[-1, 1]^N float32: joint velocities as fractions of their limits."""
    return gym.spaces.Box(-1.0, 1.0, shape=(simulator.n_joints,), dtype=np.float32)


def resolve_task(
    task: LearningTask | str | os.PathLike[str] | None, tool: str, world: str, robot: str | None
) -> LearningTask:
    """The task an environment starts from: ``task`` itself, a task file, or the shipped task of
    (tool, world, robot). Raises ValueError if a given task does not match tool and world."""
    if task is None:
        return shipped_task(tool, world, robot)
    resolved = task if isinstance(task, LearningTask) else LearningTask.load(task)
    if (resolved.tool, resolved.world) != (tool, world):
        raise ValueError(f"the task is the {resolved.tool} in {resolved.world}, not the {tool} in {world}")
    if robot is not None and resolved.robot != robot:
        raise ValueError(f"the task is for robot {resolved.robot}, not {robot}")
    return resolved


class ToolUseEnv(gym.Env):
    """One robot + tool + scene instance (see the module docstring)."""

    metadata: dict[str, Any] = {"render_modes": []}

    def __init__(
        self,
        tool: str = "spade",
        world: str = "3d",
        robot: str | None = None,
        task: LearningTask | str | os.PathLike[str] | None = None,
        scene_kwargs: dict[str, Any] | None = None,
        reward: str = "sparse",
        adr: bool = False,
    ):
        self.task = resolve_task(task, tool, world, robot)
        self.simulator = TaskSimulator(self.task, batch_size=1, scene_kwargs=scene_kwargs, reward=reward, adr=adr)
        self.observation_space = observation_space(self.simulator)
        self.action_space = action_space(self.simulator)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        return self.simulator.reset(self.np_random)[0], {}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        observation, reward, goal = self.simulator.step(np.asarray(action)[None])
        truncated = self.simulator.done
        info: dict[str, Any] = {"goal_reward": float(goal[0])}
        if truncated:
            info["is_success"] = bool(self.simulator.is_success()[0])
        return observation[0], float(reward[0]), False, truncated, info

    def tracking_action(self) -> np.ndarray:
        """(N,) the tracking controller's action now (see TaskSimulator.tracking_action)."""
        return self.simulator.tracking_action()[0].astype(np.float32)


def register_environments() -> None:
    """Register ``toolimit/<Tool><World>-v0`` for every (tool, world) of
    :func:`~toolimit.learn.shipped.environments` (idempotent)."""
    for tool, world in environments():
        name = env_id(tool, world)
        if name not in gym.registry:
            gym.register(
                name,
                entry_point="toolimit.learn.env:ToolUseEnv",
                kwargs={"tool": tool, "world": world},
                disable_env_checker=False,
            )
