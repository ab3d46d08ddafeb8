"""B copies of one task's robot, tool and scene, stepped together: the core of the environments.

The robot is kinematic, as in the paper: an action is a joint velocity, integrated over one control
step (1/24 s) and held inside the position limits, and the tool follows by forward kinematics. The
scene is batched (:mod:`toolimit.scenes.base`), so B instances cost one vectorised physics step.
Both the Gymnasium environment (B = 1) and the SB3 ``VecEnv`` (B instances) are thin layers on this
class, so there is one definition of observation, action and reward.

Observation (float32, per instance), the paper's state:
  tool position (3, m, world frame), tool quaternion (4, w first, world from tool, sign kept
  continuous along the episode), joint positions (N, rad), time (1): elapsed time t * dt since the
  reset, seconds, as the authors observed it (pyphysx_envs ``RobotEnv.get_obs``: the scene's
  simulation time).
  With ``adr=True`` (domain randomisation of the goal box, :mod:`toolimit.learn.adr`; spades only)
  two more entries follow: the goal box's offset x, y from the aligned position (world frame, in
  units of 0.1 m: :meth:`AdrBounds.observed <toolimit.learn.adr.AdrBounds.observed>`) in this
  instance, so D = 3 + 4 + N + 1 + 2.
Action: (N,) in [-1, 1], the commanded joint velocity as a fraction of each joint's action scale
  (SB3 clips actions to a symmetric normalised space), executed through the robot's
  :class:`~toolimit.robots.motion_bound.MotionBound`: for a robot with published limits (the
  Panda) the velocity and the acceleration stay within them, with the export's margins, and the
  joints brake before their position limits, so that the motion learnt is the one the export
  streams to the robot; other robots are bounded by their model's velocity and position limits.
  The authors' environment clips the commanded velocities at 3 rad/s (pyphysx_envs
  ``RobotEnv.step``), beyond the Panda's own limits (2.175 and 2.61 rad/s), bounds no
  acceleration and only penalises the excess speed; the task's ``action_limit``
  (``toolimit learn --action-limit 3``) gives that span instead, a variant past the robot's limits.
  The arm starts every episode at rest.
Reward per step (docs/original_setup.md#robot-environment): (goal reward + velocity penalty) / H, where the penalty is
  -w (|max(0, v - 0.9 v_max)| + |min(0, v + 0.9 v_max)|) (rad/s, w = 0.01) on the commanded joint
  velocity v, v_max the robot's own limits whatever the action scale. The authors' weight grew by 1e-4 per
  reset; here it is constant, so that a state earns the same return whatever the number of
  episodes before it. With ``reward="dense"`` (the paper's
  dense-reward baseline) the scene's dense shaping (the appendix's, ``Scene.dense_reward``) is
  added to the goal reward: the shaping guides, the goal reward still counts what succeeds.
Reset noise (the authors'): start joints = reference start + N(0, 0.01) rad each; every position
  parameter of the scene + N(0, 0.01) m in x and y, drawn for each instance (as each of the
  authors' environments drew its own at its reset; an instance whose draw pushes one element into
  another keeps the exact positions); the scene's own randomness (sand jitter, ...).
Goal box (spades): under ADR each instance's box is drawn inside the current ADR bounds
  (:meth:`AdrBounds.draw <toolimit.learn.adr.AdrBounds.draw>`: uniform, one position per instance;
  redrawn where it would overlap its instance's noisy deposit), without the N(0, 0.01) noise (a
  box that finds no valid position in 100 draws stands at the aligned one, and ``box_placed`` says
  so: ADR's boundary tests do not count its episode at the bound); ``reset(rng, box_positions)``
  sets the positions instead (heat maps). The bounds start collapsed on the aligned position, so
  cloning rollouts run there.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from toolimit.learn.adr import GOAL_BOX, AdrBounds, goal_box_spec
from toolimit.learn.batch_part import BatchPart
from toolimit.learn.task import LearningTask
from toolimit.robots import make_robot
from toolimit.robots.motion_bound import MotionBound
from toolimit.rotations import quaternions_wxyz
from toolimit.scenes.base import instance_params
from toolimit.scenes.registry import make_scene
from toolimit.tools import ToolPose

#: Standard deviation of the start joints' noise, rad, and of the scene positions' noise, m.
JOINT_NOISE_STD = 0.01
PARAM_NOISE_STD = 0.01
#: Weight w of the velocity penalty and the fraction of the velocity limit where it starts.
VELOCITY_PENALTY_WEIGHT = 0.01
VELOCITY_PENALTY_START = 0.9
#: The rewards a task can be learnt with: the paper's sparse goal reward, or it plus the dense shaping.
REWARDS = ("sparse", "dense")


def observation_size(n_joints: int, adr: bool) -> int:
    """D: tool position 3 + quaternion 4 + joints N + time 1 (+ goal box offset x, y under ADR)."""
    return 3 + 4 + n_joints + 1 + 2 * adr


class TaskSimulator:
    """B instances of ``task`` (see the module docstring for observation, action and reward).

    Args:
        task: the learning task (robot, scene parameters, reference, horizon).
        batch_size: B.
        scene_kwargs: keyword arguments of the scene's constructor (e.g. fewer spheres in tests).
        reward: one of :data:`REWARDS` (see the module docstring).
        adr: randomise the goal box inside ``adr_bounds`` and observe it (module docstring);
            InputError for a scene without a goal box.
        part: these B instances are a part of a larger batch (:mod:`toolimit.learn.batch_part`):
            every reset draws for the whole batch and keeps the part's share, so instance i starts
            alike however the batch is split (3D scenes; ``batch_size`` is then the part's size).
    """

    def __init__(
        self,
        task: LearningTask,
        batch_size: int = 1,
        scene_kwargs: dict[str, Any] | None = None,
        reward: str = "sparse",
        adr: bool = False,
        part: BatchPart | None = None,
    ):
        if part is not None:
            batch_size = part.size
        if int(batch_size) < 1:
            raise ValueError(f"batch_size must be >= 1, got {batch_size!r}")
        if reward not in REWARDS:
            raise ValueError(f"unknown reward {reward!r}; choose one of {', '.join(REWARDS)}")
        self.reward = reward
        self.task = task
        self.batch_size = int(batch_size)
        self.part = part or BatchPart.whole(self.batch_size)
        self.robot = make_robot(task.robot, tool=task.tool)
        if tuple(self.robot.joint_names) != tuple(task.joint_names):
            raise ValueError(
                f"task joints {list(task.joint_names)} are not robot {task.robot}'s {list(self.robot.joint_names)}"
            )
        self.scene = make_scene(task.tool, task.world, **(scene_kwargs or {}))
        if not np.isclose(self.scene.control_dt, task.control_dt):
            raise ValueError(
                f"the task's control step {task.control_dt} s differs from the scene's {self.scene.control_dt} s"
            )
        self.scene_kwargs = scene_kwargs
        self.n_joints = len(task.joint_names)
        #: What a step can command the joints (module docstring).
        self.bound = MotionBound.of(self.robot, speed=task.action_limit)
        #: (N,) rad/s: the joint velocity of an action of 1 (module docstring).
        self.action_scale = self.bound.velocity
        self.adr = adr
        self.observation_size = observation_size(self.n_joints, adr)
        #: The ADR bounds the goal box is drawn in (None without ADR); AdrCallback moves them.
        self.adr_bounds: AdrBounds | None = None
        if adr:
            axes = goal_box_spec(self.scene).axes  # InputError for a scene without a goal box
            self.adr_bounds = AdrBounds.at(task.params[GOAL_BOX], axes)
        #: (B, 2) each instance's goal box x, y (m, world frame) as the last reset set it (ADR or
        #: its ``box_positions``; zeros before).
        self.box_positions = np.zeros((self.batch_size, 2))
        #: (B,) whether each instance's box stands where the last reset meant it to: False where
        #: the ADR draw found no valid position inside the bounds and the box stands at the aligned
        #: one (True without a draw).
        self.box_placed = np.ones(self.batch_size, dtype=bool)
        self.dt = task.control_dt
        self.horizon = task.horizon
        self.q = np.zeros((self.batch_size, self.n_joints))
        #: (B, N) rad/s, the joints' velocity over the last step (zero at a reset: at rest).
        self.velocity = np.zeros((self.batch_size, self.n_joints))
        self.t = 0
        # the tool's pose at the current step (world frame), set by reset and step
        self._position = np.zeros((self.batch_size, 3))  # (B, 3) m
        self._rotation = np.zeros((self.batch_size, 3, 3))  # (B, 3, 3) world from tool
        self._quaternion = np.zeros((self.batch_size, 4))  # (B, 4) w first, sign continuous

    # ------------------------------------------------------------------------------------ episode
    def copy(self, **changes: Any) -> TaskSimulator:
        """A new simulator of the same task, batch, scene and reward, with ``changes`` to them."""
        kwargs = {
            "batch_size": self.batch_size,
            "scene_kwargs": self.scene_kwargs,
            "reward": self.reward,
            "adr": self.adr,
        }
        return TaskSimulator(self.task, **(kwargs | changes))

    def reset(
        self, rng: np.random.Generator, box_positions: np.ndarray | None = None, start: np.ndarray | None = None
    ) -> np.ndarray:
        """Start B episodes; returns the observations (B, D). ``box_positions`` (B, 2): the goal
        boxes' x, y (m, world frame) instead of the ADR draw (the heat map's grid); of the whole
        batch if this is a part of one. ``start`` (N,) rad: every instance's start joints instead
        of the reference's noisy start (the noise is drawn all the same, so the scene's draws do
        not change)."""
        part = self.part
        noise = rng.normal(0.0, JOINT_NOISE_STD, size=(part.total, self.n_joints))
        start_q = self.task.reference_q[0] + part.of(noise) if start is None else np.tile(start, (self.batch_size, 1))
        self.q = np.clip(start_q, self.bound.lower, self.bound.upper)
        self.velocity = np.zeros_like(self.q)
        box_placed = box_positions is not None or self.adr_bounds is not None
        params = self._noisy_params(rng, box_placed)
        placed = np.ones(part.total, dtype=bool)
        if box_positions is not None:
            box_positions = np.broadcast_to(np.asarray(box_positions, dtype=float), (part.total, 2))
            for i, position in enumerate(box_positions):
                if not self.box_validity(instance_params(params, i))(position):
                    self._exact_instance(params, i)  # the deposit's noise made the given box invalid
        elif self.adr_bounds is not None:
            box_positions, placed = self.adr_bounds.draw(
                rng, part.total, lambda i, position: self.box_validity(instance_params(params, i))(position)
            )
        self.box_placed = part.of(placed).copy()
        if box_positions is not None:
            self.box_positions = part.of(box_positions).copy()
            params[GOAL_BOX][:, :2] = box_positions
        part_params = {name: part.of(value) if np.ndim(value) == 2 else value for name, value in params.items()}
        self.scene.reset(part_params, part.generator(rng), self.batch_size)
        self.t = 0
        self._update_tool(first=True)
        return self.observation()

    def _noisy_params(self, rng: np.random.Generator, box_placed: bool) -> dict[str, Any]:
        """The task's scene parameters with every position (N, 3) per instance of the whole batch
        (N = ``part.total``), each with its own N(0, PARAM_NOISE_STD) m on x and y; an instance
        whose noise makes its scene invalid (an element pushed into another) keeps the exact
        values. ``box_placed``: the goal box is placed afterwards (ADR, given positions), so it
        keeps the aligned position here, which stays valid with the noisy others."""
        total = self.part.total
        noisy: dict[str, Any] = {}
        for spec in self.scene.parameters:
            value = self.task.params[spec.name]
            if spec.kind == "position":
                offsets = np.zeros((total, 3))
                if not (box_placed and spec.name == GOAL_BOX):
                    offsets[:, :2] = rng.normal(0.0, PARAM_NOISE_STD, size=(total, 2))
                value = np.asarray(value, dtype=float) + offsets
            noisy[spec.name] = value
        for i in range(total):
            if self.scene.invalid_reason(instance_params(noisy, i)) is not None:
                self._exact_instance(noisy, i)
        return noisy

    def _exact_instance(self, params: dict[str, Any], index: int) -> None:
        """Give instance ``index`` of the whole batch the task's exact positions in ``params``
        (per-instance (N, 3) arrays, changed in place)."""
        for name, value in params.items():
            if np.ndim(value) == 2:
                value[index] = self.task.params[name]

    def box_validity(self, params: dict[str, Any]) -> Callable[[np.ndarray], bool]:
        """Whether a goal box at x, y (2,) m makes a valid scene with the other ``params``."""
        goal = np.asarray(params[GOAL_BOX], dtype=float)

        def valid(position: np.ndarray) -> bool:
            return self.scene.invalid_reason(params | {GOAL_BOX: np.r_[position, goal[2]]}) is None

        return valid

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Apply actions (B, N) in [-1, 1]; returns observations (B, D), rewards (B,) and goal
        rewards (B,) after the step."""
        actions = np.asarray(actions, dtype=float).reshape(self.batch_size, self.n_joints)
        commanded = np.clip(actions, -1.0, 1.0) * self.action_scale
        q, velocity = self.bound.step(self.q, self.velocity, commanded, self.dt)
        goal = self.move_to(q, velocity)
        shaping = np.asarray(self.scene.dense_reward(), dtype=float) if self.reward == "dense" else 0.0
        reward = (goal + shaping + velocity_penalty(commanded, self.robot.velocity_limit)) / self.horizon
        return self.observation(), reward, goal

    def move_to(self, q: np.ndarray, velocity: np.ndarray | None = None) -> np.ndarray:
        """One control step with the joints set to ``q`` (B, N) rad, reached at ``velocity`` (B, N)
        rad/s (default: the difference from the last step's joints over dt); returns the goal
        rewards (B,) after it. :meth:`step` moves through it, and so does a replay of joints
        commanded open-loop (:mod:`toolimit.deploy.open_loop`), which bypasses the policy's bound."""
        q = np.asarray(q, dtype=float).reshape(self.batch_size, self.n_joints)
        self.velocity = (q - self.q) / self.dt if velocity is None else velocity
        self.q = q
        self._update_tool()
        self.scene.step(ToolPose(self._position, self._rotation))
        self.t += 1
        return np.asarray(self.scene.goal_reward(), dtype=float)

    @property
    def done(self) -> bool:
        """True once the episode has reached its horizon H."""
        return self.t >= self.horizon

    def is_success(self) -> np.ndarray:
        """(B,) the paper's success test over the steps so far."""
        return np.asarray(self.scene.is_success(), dtype=bool)

    # ------------------------------------------------------------------------------- observation
    def _update_tool(self, first: bool = False) -> None:
        positions, rotations = self.robot.tool_poses(self.q, self.task.base)
        quaternion = quaternions_wxyz(rotations)
        reference = np.where(first, np.array([1.0, 0.0, 0.0, 0.0]), self._quaternion)
        quaternion *= np.where(np.sum(quaternion * reference, axis=1, keepdims=True) < 0.0, -1.0, 1.0)
        self._position, self._rotation, self._quaternion = positions, rotations, quaternion

    def observation(self) -> np.ndarray:
        """(B, D) float32: tool position, quaternion (w first), joints, elapsed time t * dt in s (,
        goal box offset x, y from the aligned position, 0.1 m units)."""
        time = np.full((self.batch_size, 1), self.t * self.dt)
        box = [] if self.adr_bounds is None else [self.adr_bounds.observed(self.box_positions)]
        parts = [self._position, self._quaternion, self.q, time, *box]
        return np.concatenate(parts, axis=1).astype(np.float32)

    # ------------------------------------------------------------------------------------ expert
    def tracking_action(self, q: np.ndarray | None = None) -> np.ndarray:
        """(B, N) the tracking controller's action, the authors' expert for cloning: the velocity
        that reaches the reference's next configuration in one step, (q_ref[t+1] - q_t) / dt,
        as a fraction of the action scale and clipped to [-1, 1]; the reference's last
        configuration is held after its end. ``q``: joints (M, N) rad at this step instead of the
        simulator's own (a batch split over processes)."""
        target = self.task.reference_q[min(self.t + 1, self.task.reference_steps)]
        q = self.q if q is None else q
        return np.clip((target - q) / (self.dt * self.action_scale), -1.0, 1.0)


def velocity_penalty(velocity: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """(B,) -w (|max(0, v - 0.9 v_max)| + |min(0, v + 0.9 v_max)|) for joint velocities (B, N), rad/s."""
    start = VELOCITY_PENALTY_START * limit
    above = np.linalg.norm(np.maximum(0.0, velocity - start), axis=1)
    below = np.linalg.norm(np.minimum(0.0, velocity + start), axis=1)
    return -VELOCITY_PENALTY_WEIGHT * (above + below)
