"""A robot arm on a mobile base, holding a tool: forward kinematics and Jacobians of the tool frame.

Frames and coordinates (every array in SI units: metres, radians, rad/s):

* The **arm model** (``RobotModel.model``) has the robot's active joints only (locked joints removed)
  and its base at the origin of its own universe.
* The **base** ``b = (x, y, yaw)`` places the arm on the floor: the arm's universe frame sits at
  ``(x, y, base_height)`` in the world, turned by ``yaw`` about world z. It is implemented as in the
  benchmark problem (PROBLEM.md): a ``full_model`` whose first three joints are prismatic x
  (``base_x``), prismatic y (``base_y``) and revolute z (``base_yaw``), with the arm appended by
  ``pin.appendModel`` at height ``base_height``. Full configurations are ``[b, q]``
  (3 + N); base derivatives are the first three columns of the full Jacobian.
* The **tool frame** follows :mod:`toolimit.tools` (origin at the tool head, z from head to handle,
  x the working direction). By default the tool is held rigidly with its handle end at the robot's
  flange: the flange's *mount frame* (flange frame turned so that its z axis is the approach
  direction, see each robot in :mod:`toolimit.robots.arms`) carries the tool frame at
  ``(0, 0, L)`` with rotation ``diag(1, -1, -1)`` (tool z points back to the flange, tool x = mount
  x), L = ``ToolSpec.length``. ``tool_placement`` overrides that: it is the tool frame's placement
  relative to the **joint that carries the flange** (the flange frame's parent joint), exactly a
  Pinocchio ``Frame.placement``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from toolimit.errors import InputError
from toolimit.tools import ToolSpec

#: Names of the three base coordinates, in order.
BASE_COORDINATES = ("x", "y", "yaw")
#: Name of the tool frame added to both Pinocchio models.
TOOL_FRAME = "tool"
#: Velocity bound written into the base joints of ``full_model`` (m/s, rad/s); the base is static.
_BASE_VELOCITY_BOUND = 1e3


@dataclass(frozen=True)
class ArmDescription:
    """What a robot builder provides (see :mod:`toolimit.robots.arms`).

    Attributes:
        name: registry name.
        model: Pinocchio model of the active joints only, base at its universe origin (Euclidean:
            every joint revolute or prismatic, nq == nv == N).
        flange_frame: name of the frame the tool is mounted on.
        mount_rotation: (3, 3) rotation from the flange frame to the mount frame, whose z axis is
            the approach direction (pointing away from the robot, along the held tool).
        q_neutral: (N,) rest configuration, radians; the start q_0 of trajectory optimisation.
        base_height: height of the arm's universe frame above the floor, metres.
        base_dofs: (3,) bool, which of (x, y, yaw) the base may move.
        tool_base_heights: tool name -> the base height (m) when holding that tool, replacing
            ``base_height`` (the authors set the height per robot and tool); negative: the base
            stands below the scene's floor (the scene on a platform).
    """

    name: str
    model: pin.Model
    flange_frame: str
    mount_rotation: np.ndarray
    q_neutral: np.ndarray
    base_height: float
    base_dofs: tuple[bool, bool, bool] = (True, True, True)
    tool_base_heights: Mapping[str, float] = field(default_factory=dict)

    def base_height_for(self, tool: str) -> float:
        """The base height (m above the scene's floor) when holding ``tool``."""
        return float(self.tool_base_heights.get(tool, self.base_height))


def default_tool_placement(arm: ArmDescription, tool: ToolSpec) -> pin.SE3:
    """Tool frame relative to the flange's parent joint: handle end at the flange, head at L along
    the approach axis, tool z pointing back to the flange, tool x along the mount frame's x."""
    flange = arm.model.frames[arm.model.getFrameId(arm.flange_frame)]
    mount = pin.SE3(np.asarray(arm.mount_rotation, dtype=float), np.zeros(3))
    tool_in_mount = pin.SE3(np.diag([1.0, -1.0, -1.0]), np.array([0.0, 0.0, tool.length]))
    return flange.placement * mount * tool_in_mount


@dataclass
class RobotModel:
    """A robot holding a tool, on a planar mobile base (see the module docstring for frames).

    Attributes:
        name: registry name ("planar3", "panda", "ur5", "talos").
        tool: the held tool.
        model: arm-only Pinocchio model (active joints), with the frame ``"tool"``.
        full_model: base joints (x, y, yaw) followed by the arm, with the frame ``"tool"``.
        tool_frame_id: id of ``"tool"`` in ``model``; ``full_tool_frame_id`` in ``full_model``.
        joint_names: (N,) names of the arm joints, in configuration order.
        lower, upper: (N,) joint position limits, radians (from the model).
        velocity_limit: (N,) joint velocity limits, rad/s (from the model).
        q_neutral: (N,) rest configuration, radians.
        base_height: height of the base above the floor, metres.
        base_dofs: (3,) bool mask of the base coordinates (x, y, yaw) that may move.
        tool_placement: tool frame relative to the flange's parent joint.
        flange_frame: name of the flange frame.
    """

    name: str
    tool: ToolSpec
    model: pin.Model
    full_model: pin.Model
    tool_frame_id: int
    full_tool_frame_id: int
    joint_names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    velocity_limit: np.ndarray
    q_neutral: np.ndarray
    base_height: float
    base_dofs: np.ndarray
    tool_placement: pin.SE3
    flange_frame: str
    _data: pin.Data = field(init=False, repr=False)
    _full_data: pin.Data = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._data = self.model.createData()
        self._full_data = self.full_model.createData()

    @property
    def n_joints(self) -> int:
        """N, the number of arm joints."""
        return self.model.nq

    def full_configuration(self, q: np.ndarray, base: np.ndarray) -> np.ndarray:
        """(3 + N,) configuration of ``full_model`` from arm joints q (N,) and base (x, y, yaw)."""
        return np.concatenate([np.asarray(base, dtype=float), np.asarray(q, dtype=float)])

    def tool_placement_world(self, q: np.ndarray, base: np.ndarray) -> pin.SE3:
        """World placement of the tool frame for arm joints q (N,), base (3,) = (x, y, yaw)."""
        return pin.SE3(self._tool_frame(q, base))

    def tool_pose(self, q: np.ndarray, base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tool frame in the world: position (3,) metres and rotation (3, 3) (columns = tool axes)."""
        placement = self._tool_frame(q, base)
        return placement.translation.copy(), placement.rotation.copy()

    def tool_poses(self, q: np.ndarray, base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tool frames along a joint trajectory q (T, N): positions (T, 3), rotations (T, 3, 3)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        positions = np.empty((len(q), 3))
        rotations = np.empty((len(q), 3, 3))
        for t, q_t in enumerate(q):
            placement = self._tool_frame(q_t, base)
            positions[t], rotations[t] = placement.translation, placement.rotation
        return positions, rotations

    def _tool_frame(self, q: np.ndarray, base: np.ndarray) -> pin.SE3:
        """The tool frame's world placement inside the model's data: valid until the next call."""
        pin.framesForwardKinematics(self.full_model, self._full_data, self.full_configuration(q, base))
        return self._full_data.oMf[self.full_tool_frame_id]

    def tool_jacobian(self, q: np.ndarray, base: np.ndarray, reference: str = "local") -> np.ndarray:
        """(6, 3 + N) Jacobian of the tool frame w.r.t. (base x, y, yaw, arm joints).

        ``reference="local"``: twist in the tool frame (pin LOCAL); ``"world_aligned"``: linear
        velocity of the tool origin and angular velocity, both in world axes (pin
        LOCAL_WORLD_ALIGNED). Linear rows first (m per unit), angular rows last (rad per unit).
        """
        frames = {"local": pin.ReferenceFrame.LOCAL, "world_aligned": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED}
        if reference not in frames:
            raise InputError(f"reference must be one of {sorted(frames)}, got {reference!r}")
        q_full = self.full_configuration(q, base)
        pin.computeJointJacobians(self.full_model, self._full_data, q_full)
        pin.updateFramePlacements(self.full_model, self._full_data)
        return pin.getFrameJacobian(self.full_model, self._full_data, self.full_tool_frame_id, frames[reference])

    def check_configuration(self, q: np.ndarray, tolerance: float = 0.0) -> None:
        """Raise ValueError naming the joint if q (N,) is outside the position limits."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self.n_joints,):
            raise ValueError(f"{self.name}: configuration must have shape ({self.n_joints},), got {q.shape}")
        bad = np.flatnonzero((q < self.lower - tolerance) | (q > self.upper + tolerance))
        if bad.size:
            i = bad[0]
            raise ValueError(
                f"{self.name}: joint {self.joint_names[i]} = {q[i]:.4f} rad is outside "
                f"[{self.lower[i]:.4f}, {self.upper[i]:.4f}]"
            )


def build_robot_model(
    arm: ArmDescription, tool: ToolSpec, tool_placement: pin.SE3 | None, base_height: float | None
) -> RobotModel:
    """Add the tool frame to the arm and the (x, y, yaw) base joints in front of it."""
    arm_model = pin.Model(arm.model)
    flange_id = arm_model.getFrameId(arm.flange_frame)
    if flange_id >= len(arm_model.frames):
        raise ValueError(f"{arm.name}: no frame named {arm.flange_frame!r}")
    flange = arm_model.frames[flange_id]
    if tool_placement is not None and not isinstance(tool_placement, pin.SE3):
        raise ValueError(f"tool_placement must be a pinocchio SE3, got {type(tool_placement).__name__}")
    placement = default_tool_placement(arm, tool) if tool_placement is None else pin.SE3(tool_placement)
    tool_frame_id = arm_model.addFrame(
        pin.Frame(TOOL_FRAME, flange.parentJoint, flange_id, placement, pin.FrameType.OP_FRAME)
    )
    height = arm.base_height_for(tool.name) if base_height is None else float(base_height)
    if not np.isfinite(height):
        raise ValueError(f"base_height must be finite, got {base_height}")

    base = pin.Model()
    joint_x = base.addJoint(0, pin.JointModelPX(), pin.SE3.Identity(), "base_x")
    joint_y = base.addJoint(joint_x, pin.JointModelPY(), pin.SE3.Identity(), "base_y")
    joint_yaw = base.addJoint(joint_y, pin.JointModelRZ(), pin.SE3.Identity(), "base_yaw")
    for limit in ("velocityLimit", "lowerVelocityLimit", "upperVelocityLimit"):
        setattr(base, limit, np.full(3, _BASE_VELOCITY_BOUND))  # unbounded in practice, but ordered
    mount_frame = base.addFrame(pin.Frame("base_mount", joint_yaw, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    full_model = pin.appendModel(base, arm_model, mount_frame, pin.SE3(np.eye(3), np.array([0.0, 0.0, height])))

    n = arm_model.nq
    joint_names = tuple(arm_model.names[1:])
    velocity_limit = np.array(arm_model.velocityLimit, dtype=float)
    if not np.all(np.isfinite(velocity_limit) & (velocity_limit > 0)):
        raise ValueError(f"{arm.name}: velocity limits must be positive and finite, got {velocity_limit}")
    return RobotModel(
        name=arm.name,
        tool=tool,
        model=arm_model,
        full_model=full_model,
        tool_frame_id=tool_frame_id,
        full_tool_frame_id=full_model.getFrameId(TOOL_FRAME),
        joint_names=joint_names,
        lower=np.array(arm_model.lowerPositionLimit, dtype=float),
        upper=np.array(arm_model.upperPositionLimit, dtype=float),
        velocity_limit=velocity_limit,
        q_neutral=np.asarray(arm.q_neutral, dtype=float).reshape(n).copy(),
        base_height=height,
        base_dofs=np.array(arm.base_dofs, dtype=bool),
        tool_placement=placement,
        flange_frame=arm.flange_frame,
    )
