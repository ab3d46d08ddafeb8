"""The scene protocol: one interface for every tool and both worlds (planar and 3D).

A scene is a small simulated world that a tool moves through kinematically. Alignment samples its
parameters, replays a demonstration in it and reads the goal reward; robot execution and learning
use the same calls. Frames: world, metres, z up, ground at z = 0; planar scenes use the plane they
document (x-z vertical plane or x-y horizontal plane) and ignore the other coordinate.

Scenes are *batched*: ``reset(..., batch_size=B)`` creates B independent instances of the same
parameters, each with its own randomness where the scene has some (the planar sand's jitter, the
grass's placement), so the 10 replays of an alignment sample run as one call. A position
parameter may also be given per instance, (B, 3) (the learner's reset noise, domain
randomisation's goal boxes). Every per-instance quantity has the batch on axis 0; B = 1 is the
ordinary case.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal, Protocol, runtime_checkable

import numpy as np

from toolimit.errors import InvalidSceneParameters
from toolimit.tools import ToolPose, tool_spec

#: Control rate of the paper: scenes step the tool at this rate and sub-step their physics.
CONTROL_FPS = 24.0

#: Half side of the square world (m, world x and y) every scene element stands in.
WORLD_HALF_SIZE = 5.0

#: A step-counting scene (the spades) succeeds when its goal was met on at least this fraction of
#: the steps since reset (the paper: the goal holds for half of the episode).
SUCCESS_FRACTION = 0.5

#: Scene parameter values: a position parameter is a (3,) world point, a uniform one a float.
SceneParams = Mapping[str, "np.ndarray | float"]

#: Prefix of a scene parameter's key in the pipeline's ``.npz`` files (``param_<name>``).
PARAM_PREFIX = "param_"


def pack_scene_params(params: SceneParams) -> dict[str, np.ndarray]:
    """``params`` as ``.npz`` arrays keyed ``param_<name>`` (floats as 0-d arrays); the one writer of
    scene parameters in the pipeline's files (aligned demo, candidates, trajectory, task)."""
    return {PARAM_PREFIX + name: np.asarray(value, dtype=float) for name, value in params.items()}


def unpack_scene_params(arrays: Mapping[str, np.ndarray]) -> dict[str, np.ndarray | float]:
    """The ``param_<name>`` arrays of a loaded ``.npz`` as scene parameters (0-d arrays as floats,
    stacked candidates keep their leading axis); the one reader of :func:`pack_scene_params`."""
    return {
        key.removeprefix(PARAM_PREFIX): float(value) if np.ndim(value) == 0 else np.asarray(value, dtype=float)
        for key, value in arrays.items()
        if key.startswith(PARAM_PREFIX)
    }


#: b (1/m^2) of the paper appendix's dense rewards (docs/original_setup.md#dense-rewards,
#: the dense-reward baseline): every term is exp(-0.5 b d^2) of a distance d (m), a
#: length scale 1 / sqrt(b) of about 0.32 m.
DENSE_REWARD_B = 10.0
#: The appendix's weights: of the spade's tool-to-deposit term (its sand term has weight 1) and of
#: the scythe's tool-to-patch term.
DENSE_SPADE_TOOL_WEIGHT = 0.05
DENSE_SCYTHE_WEIGHT = 0.1


def dense_tool_point(tool: str) -> np.ndarray:
    """(3,) the tool-frame point (m) whose distance the dense reward of ``tool`` measures, the point
    of the authors' code (pyphysx_envs ``scenes/*TaskScene.py``): the spade's handle end (their
    spade body's origin, ``tool.get_global_pose()``), the hammer's striking face (their hammer's
    ``to_tip_transform``: the head's end along its striking axis), the scythe's head point (their
    scythe's tip, on the snath at the blade's mid-width); the head point for another tool."""
    spec = tool_spec(tool)
    if tool == "spade":
        return np.array([0.0, 0.0, spec.length])
    if tool == "hammer":
        return np.array([spec.head_width / 2.0, 0.0, 0.0])
    return np.zeros(3)


@dataclass(frozen=True)
class ParameterSpec:
    """One scene parameter and how alignment samples it.

    Attributes:
        name: key in the parameter mapping.
        kind: ``"position"``: a world point (3,) of a scene element, sampled by alignment from the
            Gaussian mixture around the demonstration's keypoints; ``"uniform"``: a scalar sampled
            uniformly in ``[low, high]``.
        low, high: for ``"uniform"``, the bounds (floats); for ``"position"``, (3,) bounds of the
            element's admissible position (world frame, m); :func:`parameter_violation` rejects a
            value outside them.
        on_ground: for ``"position"``: the element stands on the ground, so alignment sets z = 0.
        unit: unit of a uniform parameter ("m", "rad", ...), for reports.
        description: one line for reports and notebooks.
        axes: for ``"position"``: the coordinates (0 = x, 1 = y, 2 = z) the scene reads and checks
            against the bounds; a planar scene ignores the others.
        bound_reason: why the bounds are what they are, added to the message of a value outside them.

    A ``"position"`` parameter's value is one (3,) point for every instance, or to ``reset`` a
    (B, 3) array, one point per instance; ``invalid_reason`` and ``footprints`` take one
    instance's (3,) value.
    """

    name: str
    kind: Literal["position", "uniform"]
    low: float | tuple[float, float, float]
    high: float | tuple[float, float, float]
    on_ground: bool = True
    unit: str = ""
    description: str = ""
    axes: tuple[int, ...] = (0, 1, 2)
    bound_reason: str = ""


def world_position(
    name: str,
    description: str,
    low_z: float = 0.0,
    high_z: float = 0.0,
    axes: tuple[int, ...] = (0, 1, 2),
    bound_reason: str = "",
) -> ParameterSpec:
    """A ``"position"`` spec (unit m) whose x and y may be anywhere in the world (within
    +-``WORLD_HALF_SIZE``) and whose z lies in [``low_z``, ``high_z``]; the default z = 0 is an
    element standing on the ground (alignment then sets z = 0)."""
    return ParameterSpec(
        name,
        "position",
        low=(-WORLD_HALF_SIZE, -WORLD_HALF_SIZE, low_z),
        high=(WORLD_HALF_SIZE, WORLD_HALF_SIZE, high_z),
        on_ground=low_z == high_z == 0.0,
        unit="m",
        description=description,
        axes=axes,
        bound_reason=bound_reason,
    )


@runtime_checkable
class Scene(Protocol):
    """What every scene offers. See the module docstring for frames and batching.

    Attributes:
        tool: the tool name this scene is for ("spade", "hammer", "scythe").
        world: "planar" or "3d".
        control_dt: time of one ``step``, seconds (1 / CONTROL_FPS unless built otherwise).
        parameters: the parameter specs, in a fixed order.
        batch_size: B, the number of instances since the last ``reset``.
    """

    tool: str
    world: str
    control_dt: float
    parameters: tuple[ParameterSpec, ...]
    batch_size: int

    def invalid_reason(self, params: SceneParams) -> str | None:
        """Why ``params`` cannot make a valid scene (overlap, out of bounds), or None if it can."""

    def reset(self, params: SceneParams, rng: np.random.Generator, batch_size: int = 1) -> None:
        """Build B instances with these parameters; raises InvalidSceneParameters if invalid.

        A position parameter may be (B, 3): one point per instance (ParameterSpec).

        The tool is absent until the first ``step``, which places it without velocity.
        """

    def step(self, tool_pose: ToolPose) -> None:
        """Move the tool kinematically to ``tool_pose`` over ``control_dt`` and simulate.

        ``tool_pose`` arrays are (3,) and (3, 3) for all instances, or (B, 3) and (B, 3, 3). The
        tool's velocity is the pose difference over ``control_dt``, so impacts transfer momentum.
        """

    def goal_reward(self) -> np.ndarray:
        """(B,) sparse goal reward now (spade: spheres in the box; hammer: 1 if the nail is in;
        scythe: stalks cut)."""

    def dense_reward(self) -> np.ndarray:
        """(B,) dense shaping reward of the paper's appendix as the authors' code has it, for the
        dense-reward baseline: sums of :func:`gaussian_closeness` terms (:func:`dense_spade_reward`
        in [0, 1.05], :func:`dense_hammer_reward` [0, 1], :func:`dense_scythe_reward` [0, 0.1]) on
        the tool's :func:`dense_tool_point`, per step, not divided by the horizon (the learning
        environment does that)."""

    def is_success(self) -> np.ndarray:
        """(B,) bool: the paper's success test over the steps so far (see docs/method.md#success-criteria)."""

    def footprints(self, params: SceneParams) -> np.ndarray:
        """(M, 5) ground rectangles the scene elements of ``params`` stand on, world x-y plane:
        centre x, centre y (m), half-length along the element's own x, half-width (m), yaw (rad).

        A pure function of valid ``params`` (no reset needed; elements that move later are where
        they start). A robot base must not stand inside one. Planar x-z scenes give a large
        half-width (their elements span the y axis).
        """

    def snapshot(self) -> dict[str, np.ndarray]:
        """Arrays describing the current state of instance 0 for views (element positions, ...)."""


# --- helpers for scene implementations -----------------------------------------------------------
class SceneBase:
    """The set-up every scene's constructor shares: its timing (checked), no instances before the
    first ``reset``, and the parameter check driven by the scene's specs.

    Subclasses set ``tool``, ``world`` and ``parameters`` (see :class:`Scene`) and override
    :meth:`invalid_reason` only to add checks the specs cannot express (an overlap).

    Args:
        control_dt: duration of one ``step``, s.
        substeps: physics (or cut-test) sub-steps per control step.
    """

    tool: str
    world: str
    parameters: tuple[ParameterSpec, ...]

    def __init__(self, control_dt: float, substeps: int) -> None:
        require_positive(control_dt=control_dt)
        require_counts(substeps=substeps)
        self.control_dt = float(control_dt)
        self.substeps = int(substeps)
        self.batch_size = 0  # B, set by reset

    def invalid_reason(self, params: SceneParams) -> str | None:
        """Why ``params`` cannot make this scene (against its parameter specs), or None."""
        return parameter_violation(self.parameters, params)


def parameter_violation(parameters: tuple[ParameterSpec, ...], params: SceneParams) -> str | None:
    """Why ``params`` do not meet the specs, or None: a missing name, a position that is not a finite
    (3,) world point or lies outside [low, high] on one of its ``axes``, a uniform value that is not a
    number in [low, high]. A scene adds its own rules (overlap) after this check."""
    for spec in parameters:
        if spec.name not in params:
            return f"missing parameter {spec.name!r}"
        value = np.asarray(params[spec.name], dtype=float)
        if spec.kind == "uniform":
            low, high = float(spec.low), float(spec.high)  # type: ignore[arg-type]
            if value.shape != () or not np.isfinite(value) or not low <= value <= high:
                return f"{spec.name} must be a number in [{low:.4g}, {high:.4g}], got {value.tolist()}"
            continue
        if value.shape != (3,) or not np.all(np.isfinite(value)):
            return f"parameter {spec.name!r} must be a finite (3,) world point, got {value.tolist()} of shape {value.shape}"
        lows, highs = np.broadcast_to(spec.low, 3), np.broadcast_to(spec.high, 3)
        for axis in spec.axes:
            if not lows[axis] <= value[axis] <= highs[axis]:
                reason = f" ({spec.bound_reason})" if spec.bound_reason else ""
                return (
                    f"{spec.name} {'xyz'[axis]} = {value[axis]:.3f} m is outside the world bound "
                    f"[{lows[axis]:.4g}, {highs[axis]:.4g}] m{reason}"
                )
    return None


def gaussian_closeness(distance_squared: np.ndarray) -> np.ndarray:
    """exp(-0.5 b d^2) of squared distances d^2 (m^2), b = :data:`DENSE_REWARD_B`: the term of
    every dense reward, 1 at distance 0, 0.61 at 0.32 m, 0.007 at 1 m."""
    return np.exp(-0.5 * DENSE_REWARD_B * np.asarray(distance_squared, dtype=float))


def dense_hammer_reward(tool_point: np.ndarray | None, nail_head: np.ndarray) -> np.ndarray:
    """(B,) the appendix's hammer shaping, in [0, 1]: the closeness of the hammer's striking face
    (:func:`dense_tool_point`) to the nail head's centre (the authors' nail body's origin); 0
    before the hammer is placed.

    Args:
        tool_point: (B, D) striking face centres, None before the first step.
        nail_head: (B, D) nail head centres where the nails are now.
        Both in the world frame (D = 3) or in the planar scene's plane (D = 2), m.
    """
    if tool_point is None:
        return np.zeros(len(nail_head))
    return gaussian_closeness(np.sum((tool_point - nail_head) ** 2, axis=-1))


def dense_scythe_reward(tool_point: np.ndarray | None, patch: np.ndarray) -> np.ndarray:
    """(B,) the appendix's scythe shaping, in [0, 0.1]: :data:`DENSE_SCYTHE_WEIGHT` times the
    closeness of the scythe's head point (:func:`dense_tool_point`) to the grass patch's centre on
    the ground (the authors' mean over their one patch); 0 before the scythe is placed.

    Args:
        tool_point: (B, D) head points, None before the first step.
        patch: (B, D) the patch's centre, per instance.
        Both in the world frame (D = 3) or in the planar scene's plane (D = 2), m.
    """
    if tool_point is None:
        return np.zeros(len(patch))
    return DENSE_SCYTHE_WEIGHT * gaussian_closeness(np.sum((tool_point - patch) ** 2, axis=-1))


def dense_spade_reward(
    grains: np.ndarray, goal: np.ndarray, tool_point: np.ndarray | None, deposit: np.ndarray
) -> np.ndarray:
    """(B,) the appendix's spade shaping, in [0, 1.05]: the mean over the sand grains of their
    closeness to the goal box's floor centre, plus :data:`DENSE_SPADE_TOOL_WEIGHT` times the
    closeness of the spade's handle end (:func:`dense_tool_point`) to the deposit's floor centre
    (no tool term before the spade is placed); the authors' points (their boxes' and spade's body
    origins).

    Args:
        grains: (B, N, D) sand grain (circle or sphere) centres.
        goal: (B, 1, D) the goal box's floor centre (on the ground).
        tool_point: (B, D) handle ends, None before the first step.
        deposit: (D,) or (B, D) the deposit's floor centre.
        All in the world frame (D = 3) or in the planar scene's plane (D = 2), m.
    """
    sand_term = gaussian_closeness(np.sum((grains - goal) ** 2, axis=-1)).mean(axis=1)
    if tool_point is None:
        return sand_term
    tool_term = gaussian_closeness(np.sum((tool_point - deposit) ** 2, axis=-1))
    return sand_term + DENSE_SPADE_TOOL_WEIGHT * tool_term


def require_reset(scene: Scene | SceneBase) -> None:
    """RuntimeError unless ``scene`` was reset (its batch size is 0 until then)."""
    if scene.batch_size == 0:
        raise RuntimeError(f"{type(scene).__name__}: call reset() first")


class SuccessTracker:
    """Per instance, the steps since reset on which the goal was met; success is meeting it on at
    least :data:`SUCCESS_FRACTION` of them (the spades' test)."""

    def __init__(self, batch_size: int) -> None:
        self.steps = 0
        self.successful_steps = np.zeros(batch_size, dtype=int)  # (B,)

    def record(self, goal_met: np.ndarray) -> None:
        """Count one step; ``goal_met`` (B,) bool says where the goal was met at its end."""
        self.steps += 1
        self.successful_steps += goal_met

    def is_success(self) -> np.ndarray:
        """(B,) bool; False everywhere before the first step."""
        if self.steps == 0:
            return np.zeros(len(self.successful_steps), dtype=bool)
        return self.successful_steps >= SUCCESS_FRACTION * self.steps


class GoalTimer:
    """Per instance, when the goal was first met on the scene's clock; success is meeting it within
    the scene's success window (the hammers' and scythes' test: the paper's "within the first
    second"). The scene says when its clock starts (the first step, or the tool's placement)."""

    def __init__(self, batch_size: int) -> None:
        self.time = 0.0  # s on the scene's clock
        self.met_at = np.full(batch_size, np.inf)  # (B,) s; inf where the goal was not met yet

    def advance(self, dt: float) -> None:
        """Move the clock on by ``dt`` seconds."""
        self.time += dt

    def record(self, goal_met: np.ndarray | np.bool_, at: np.ndarray | float | None = None) -> None:
        """Note the goal met where ``goal_met`` (B,) bool says so for the first time, at ``at``
        ((B,) or () s; the clock's time when None)."""
        when = self.time if at is None else at
        self.met_at = np.where(goal_met & np.isinf(self.met_at), when, self.met_at)

    def within(self, window: float) -> np.ndarray:
        """(B,) bool: the goal was met at most ``window`` seconds after the clock's start."""
        return self.met_at <= window + 1e-9


class WindowedGoalScene(SceneBase):
    """A scene that succeeds where its goal was met within ``success_window`` seconds of the start
    of its clock (the hammers and the scythes: the paper's "within the first second", docs/method.md#success-criteria).

    The subclass starts the clock, :attr:`goal_timer`, with the first ``step`` after ``reset`` (each
    scene says at which instant), advances it and records when the goal is met.

    Args:
        control_dt, substeps: see :class:`SceneBase`.
        success_window: the goal must be met within this many seconds of the clock's start, s.
    """

    def __init__(self, control_dt: float, substeps: int, success_window: float) -> None:
        super().__init__(control_dt, substeps)
        self.success_window = float(success_window)
        self.goal_timer = GoalTimer(0)  # replaced by reset

    def start_instances(self, batch_size: int) -> None:
        """For ``reset``: B instances, none of which has met its goal, on a clock at 0."""
        self.batch_size = batch_size
        self.goal_timer = GoalTimer(batch_size)

    def is_success(self) -> np.ndarray:
        """(B,) bool: the goal was met within ``success_window`` s of the clock's start."""
        require_reset(self)
        return self.goal_timer.within(self.success_window)


def check_reset(scene: Scene, params: SceneParams, batch_size: int) -> int:
    """Validate a ``reset`` call before any work; returns B as an int.

    A position parameter given as (B, 3) is checked instance by instance (the message names the
    instance). Raises InvalidSceneParameters with the scene's own reason, or ValueError for a
    batch size < 1 or a per-instance array that is not (B, 3).
    """
    if int(batch_size) < 1:
        raise ValueError(f"batch_size must be >= 1, got {batch_size!r}")
    batched = [
        spec.name
        for spec in scene.parameters
        if spec.kind == "position" and spec.name in params and np.ndim(params[spec.name]) == 2
    ]
    for name in batched:
        if np.shape(params[name]) != (batch_size, 3):
            raise ValueError(f"per-instance {name} must be ({batch_size}, 3), got {np.shape(params[name])}")
    for b in range(int(batch_size) if batched else 1):
        reason = scene.invalid_reason(instance_params(params, b))
        if reason is not None:
            raise InvalidSceneParameters(f"instance {b}: {reason}" if batched else reason)
    return int(batch_size)


def instance_params(params: SceneParams, index: int) -> dict[str, np.ndarray | float]:
    """Instance ``index``'s parameters: row ``index`` of every per-instance (B, 3) position, the
    other values as they are."""
    return {name: np.asarray(value)[index] if np.ndim(value) == 2 else value for name, value in params.items()}


def instance_positions(params: SceneParams, name: str, batch_size: int) -> np.ndarray:
    """(B, 3) the position parameter ``name`` of every instance: a (3,) value repeated, or the
    (B, 3) per-instance values, world frame, m."""
    return np.broadcast_to(np.asarray(params[name], dtype=float), (batch_size, 3)).copy()


def batched_pose(tool_pose: ToolPose, batch_size: int) -> tuple[np.ndarray, np.ndarray]:
    """A ``step``'s pose as (B, 3) head positions (m) and (B, 3, 3) world-from-tool rotations,
    broadcasting a single pose to every instance.

    Raises ValueError naming the bad shape or non-finite value.
    """
    position = np.asarray(tool_pose.position, dtype=float)
    rotation = np.asarray(tool_pose.rotation, dtype=float)
    if position.shape not in ((3,), (batch_size, 3)):
        raise ValueError(f"tool_pose.position must have shape (3,) or ({batch_size}, 3), got {position.shape}")
    if rotation.shape not in ((3, 3), (batch_size, 3, 3)):
        raise ValueError(f"tool_pose.rotation must have shape (3, 3) or ({batch_size}, 3, 3), got {rotation.shape}")
    if not (np.all(np.isfinite(position)) and np.all(np.isfinite(rotation))):
        raise ValueError("tool_pose contains non-finite values")
    position = np.broadcast_to(position, (batch_size, 3)).copy()
    rotation = np.broadcast_to(rotation, (batch_size, 3, 3)).copy()
    return position, rotation


def require_positive(**values: float) -> None:
    """Raise ValueError naming the first argument that is not a positive finite number."""
    for name, value in values.items():
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive number, got {value!r}")


def require_counts(**counts: int) -> None:
    """Raise ValueError naming the first count (sub-steps, stalks, ...) below 1."""
    for name, count in counts.items():
        if int(count) < 1:
            raise ValueError(f"{name} must be >= 1, got {count!r}")
