"""Conformance: every registered tool (in each world it has a scene) and every registered robot goes
through the whole pipeline on the tiniest budget that proves the wiring.

synthetic demonstration -> alignment (first candidate, one replay) -> trajectory optimisation (two
starts, two SQP iterations) -> learning task -> ``gymnasium``'s ``check_env`` on ``ToolUseEnv``.

The cases are read from the registries, so a tool or robot registered in the package is tested here
without new test code. Two registrations made from user code go through the same test: a toy tool
(its record, scene class and synthetic motion are all in this file) and example-robot-data's xArm7,
which toolimit does not ship; both are registered for their case only (the registries are restored
after it).
"""

from __future__ import annotations

import dataclasses
import functools

import example_robot_data
import numpy as np
import pinocchio as pin
import pytest
from gymnasium.utils.env_checker import check_env

from toolimit.align import AlignmentConfig, AlignmentResult, align
from toolimit.demos import synthesize_demo
from toolimit.demos.synthetic import Knot, KnotMotion, hand_from_head, hand_tool_points
from toolimit.learn import task_from_trajectory
from toolimit.learn.env import ToolUseEnv
from toolimit.robots import ROBOTS, ArmDescription, make_robot, register_robot
from toolimit.robots import registry as robot_registry
from toolimit.scenes import available_scenes, make_scene
from toolimit.scenes.base import SceneBase, check_reset, instance_positions, world_position
from toolimit.tools import ToolPose, ToolRecord, ToolSpec, register_tool, tool_record, tool_records
from toolimit.tools import registry as tool_registry
from toolimit.trajopt import SqpOptions, TrackOptions, targets_from_alignment, track

SEED = 0
#: Alignment: stop at the first sample that earns a reward in its one replay.
TINY_ALIGNMENT = AlignmentConfig(samples=200, candidates=1, replays=1, accept_replays=1, screen_replays=0)
#: Trajectory optimisation: two starts (opposite sides of the ring around the targets) from the held
#: rest pose, two SQP iterations; a start's base may stop inside a scene element (on seed 0 the first
#: start's stops in the scythe's grass patch) and the other then stands clear.
TINY_TRACKING = TrackOptions(starts=2, sqp=SqpOptions(max_iterations=2), initialisations=("hold",))


# --- a toy tool, registered from user code ----------------------------------------------------------
class ToyTouchScene(SceneBase):
    """The toy tool's planar x-z scene: one target on the ground; an instance earns reward 1 once
    the tool head (m, world frame) comes within ``radius`` of it."""

    tool = "toy"
    world = "planar"

    def __init__(self, radius: float = 0.1, control_dt: float = 1.0 / 24.0) -> None:
        super().__init__(control_dt, substeps=1)
        self.radius = radius
        self.parameters = (world_position("target", "the point to touch", axes=(0, 2)),)

    def reset(self, params, rng: np.random.Generator, batch_size: int = 1) -> None:
        self.batch_size = check_reset(self, params, batch_size)
        self.target = instance_positions(params, "target", batch_size)  # (B, 3): the learner's noise per instance
        self.touched = np.zeros(batch_size, bool)
        self.head = np.zeros((batch_size, 3))

    def step(self, tool_pose: ToolPose) -> None:
        self.head = np.broadcast_to(tool_pose.position, (self.batch_size, 3)).copy()
        distance = np.linalg.norm((self.head - self.target)[:, [0, 2]], axis=1)
        self.touched |= distance < self.radius

    def goal_reward(self) -> np.ndarray:
        return self.touched.astype(float)

    def dense_reward(self) -> np.ndarray:
        return np.exp(-5.0 * np.linalg.norm(self.head - self.target, axis=1) ** 2)

    def is_success(self) -> np.ndarray:
        return self.touched.copy()

    def footprints(self, params) -> np.ndarray:
        target = np.asarray(params["target"], dtype=float)
        return np.array([[target[0], 0.0, 0.02, 10.0, 0.0]])

    def snapshot(self) -> dict[str, np.ndarray]:
        return {"target": self.target[0].copy()}


def toy_knots(rng: np.random.Generator, fps: float) -> KnotMotion:
    """Rest, reach down to touch the ground 0.3-0.4 m ahead, come back (hand coordinates of
    :mod:`toolimit.demos.synthetic`)."""
    length = 0.3
    rest = hand_from_head([0.0, 0.0, 0.3], 0.5, 0.0, length)
    touch = hand_from_head([rng.uniform(0.3, 0.4), 0.0, 0.01], 0.8, 0.0, length)
    frames = np.cumsum([0, int(0.5 * fps), int(fps), int(fps), int(0.5 * fps)])
    knots = [Knot(int(f), q, np.zeros(5), np.zeros(5)) for f, q in zip(frames, [rest, rest, touch, rest, rest])]
    return knots, lambda q: hand_tool_points(q, length), {"touch": [int(frames[2])]}, {}


TOY = ToolRecord(
    spec=ToolSpec("toy", length=0.3, head_length=0.05, head_width=0.05),
    scenes={"planar": f"{__name__}:ToyTouchScene"},
    synthetic_motion=f"{__name__}:toy_knots",
)


# --- a robot toolimit does not ship, registered from user code ------------------------------------
def xarm7() -> ArmDescription:
    """example-robot-data's xArm7 (7 joints, no gripper), tool on ``link_eef``, base on the floor."""
    robot = example_robot_data.load("xarm7")
    return ArmDescription(
        name="xarm7",
        model=pin.Model(robot.model),
        flange_frame="link_eef",
        mount_rotation=np.eye(3),
        q_neutral=np.array([0.0, -0.3, 0.0, 1.0, 0.0, 1.3, 0.0]),
        base_height=0.0,
    )


@pytest.fixture
def user_registrations(monkeypatch):
    """The toy tool and the xArm7 registered through the public API, for this test only."""
    monkeypatch.setattr(tool_registry, "_RECORDS", dict(tool_registry._RECORDS))
    monkeypatch.setattr(robot_registry, "_BUILDERS", dict(robot_registry._BUILDERS))
    register_tool(TOY)
    register_robot("xarm7", xarm7)


# --- the cases --------------------------------------------------------------------------------------
def robot_world(robot: str) -> str:
    """The world a robot works in: a base that cannot move sideways (y) keeps an arm in its x-z
    plane, the planar world's; any other robot works in 3D."""
    return "3d" if make_robot(robot).base_dofs[1] else "planar"


def holder(tool: str, world: str) -> str:
    """The robot of ``tool`` in ``world``: its default robot there, else the first registered robot
    that works in that world."""
    default = tool_record(tool).default_robots.get(world)
    return default or next(robot for robot in ROBOTS if robot_world(robot) == world)


@functools.cache
def aligned(tool: str, world: str) -> AlignmentResult:
    """The tool's synthetic demonstration aligned to its scene (one per pair, shared by the cases)."""
    demo = synthesize_demo(tool, seed=SEED)
    result = align(demo, tool, world, TINY_ALIGNMENT, seed=SEED, workers=1, progress=False)
    assert result.candidates, f"no candidate for the {tool} in {world} within {TINY_ALIGNMENT.samples} samples"
    return result


def run_pipeline(tool: str, world: str, robot_name: str) -> None:
    """Align, track, make the learning task and check its environment."""
    result = aligned(tool, world)
    params = result.best.sample.params
    scene = make_scene(tool, world)
    robot = make_robot(robot_name, tool)
    options = dataclasses.replace(TINY_TRACKING, footprints=scene.footprints(params))
    trajectory = track(robot, targets_from_alignment(result), options, rng=np.random.default_rng(SEED))
    assert np.all(np.isfinite(trajectory.q)) and tuple(trajectory.joint_names) == robot.joint_names
    task = task_from_trajectory(trajectory, world, params, robot, scene, seed=SEED)
    assert (task.tool, task.world, task.robot) == (tool, world, robot_name)
    check_env(ToolUseEnv(tool, world, task=task), skip_render_check=True)


@pytest.mark.parametrize(("tool", "world"), available_scenes(), ids=[f"{t}-{w}" for t, w in available_scenes()])
def test_every_registered_tool_goes_through_the_pipeline(tool, world):
    run_pipeline(tool, world, holder(tool, world))


@pytest.mark.parametrize("robot", tuple(ROBOTS))
def test_every_registered_robot_goes_through_the_pipeline(robot):
    world = robot_world(robot)
    tool = next(record.name for record in tool_records() if world in record.scenes)
    run_pipeline(tool, world, robot)


def test_a_tool_registered_from_user_code_goes_through_the_pipeline(user_registrations):
    assert ("toy", "planar") in available_scenes()
    run_pipeline("toy", "planar", holder("toy", "planar"))


def test_a_robot_registered_from_user_code_goes_through_the_pipeline(user_registrations):
    assert "xarm7" in ROBOTS
    test_every_registered_robot_goes_through_the_pipeline("xarm7")
