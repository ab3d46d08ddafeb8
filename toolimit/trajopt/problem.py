"""The tracking problem: a robot on a mobile base follows target tool poses with its tool frame.

Decision variables: the base ``b`` (its active coordinates among x, y, yaw; metres, radians) and
the joint velocities ``v_1..v_T`` (rad/s); ``q_t = q_{t-1} + dt v_t`` with ``q_0`` given. Cost

    J = sum_{t=1..T} [ 1/2 |W log6(P_t^-1 M(b, q_t))|^2 + 1/2 w_v |v_t|^2 ]

with ``M`` the tool frame in the world, ``log6`` Pinocchio's (linear part first; the error in the
tool's LOCAL frame) and ``W = diag(w_pos I3, w_rot I3)``. Joint position and velocity limits are
hard constraints, so J equals the benchmark's objective (PROBLEM.md) whenever they hold.
This module evaluates J and its Gauss-Newton linearisation; each term of J is defined once in
:mod:`toolimit.trajopt.costs`, and :mod:`toolimit.trajopt.sqp` solves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from toolimit.errors import InputError, InvalidSetting
from toolimit.robots import RobotModel
from toolimit.robots.motion_bound import MotionBound
from toolimit.tools import ToolPose
from toolimit.trajopt.costs import CostTerm, Iterate, Point, PoseTerm, PostureTerm, VelocityTerm


@dataclass(frozen=True)
class TrackingWeights:
    """Weights of the cost J (see the module docstring).

    Attributes:
        position: w_pos, on the position part of log6 (metres).
        rotation: w_rot, on the rotation part of log6 (radians).
        velocity: w_v, on the joint velocities (rad/s) squared. 1e-4 by default, the value measured
            to work in the pipeline: on ``spade_03`` in the planar world (the ``--quick`` alignment's
            3 candidates, 8 starts) no robot replay earned anything with 0.01 (two candidates
            tracked upside down, the third short of the box), and the selected one 35.1 spheres
            with 1e-4. The shared benchmark problem's 0.01 is passed by its benchmark.
        posture: w_p, on the joints' distance to the start configuration q_0 (rad) squared, an
            optional term that keeps a redundant arm near its rest posture; 0 (the default) leaves
            J exactly as above.
    """

    position: float = 1.0
    rotation: float = 0.5
    velocity: float = 1e-4
    posture: float = 0.0

    def __post_init__(self) -> None:
        for name in ("position", "rotation", "velocity", "posture"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise InvalidSetting(f"{name}_weight", f"must be a finite number >= 0, got {value}")

    @property
    def pose_diagonal(self) -> np.ndarray:
        """(6,) diagonal of W."""
        return np.array([self.position] * 3 + [self.rotation] * 3)


@dataclass(frozen=True)
class PoseTargets:
    """Target tool-frame poses P_1..P_T in the world frame.

    Attributes:
        positions: (T, 3) tool-frame origins (tool head), metres.
        rotations: (T, 3, 3) tool-frame orientations (columns = tool axes in world axes).
        fps: frame rate of the demonstration, Hz (the time step is time_scale / fps).
    """

    positions: np.ndarray
    rotations: np.ndarray
    fps: float

    def __post_init__(self) -> None:
        positions = np.asarray(self.positions, dtype=float)
        rotations = np.asarray(self.rotations, dtype=float)
        if positions.ndim != 2 or positions.shape[1] != 3 or len(positions) < 1:
            raise InputError(f"target positions must have shape (T, 3) with T >= 1, got {positions.shape}")
        if rotations.shape != (len(positions), 3, 3):
            raise InputError(f"target rotations must have shape ({len(positions)}, 3, 3), got {rotations.shape}")
        if not (np.all(np.isfinite(positions)) and np.all(np.isfinite(rotations))):
            raise InputError("target poses contain non-finite values")
        orthogonality = np.abs(np.swapaxes(rotations, 1, 2) @ rotations - np.eye(3)).max()
        if orthogonality > 1e-6 or np.any(np.linalg.det(rotations) < 0):
            raise InputError(f"target rotations must be proper rotations (max |R^T R - I| = {orthogonality:.2e})")
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise InputError(f"fps must be positive, got {self.fps}")
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "rotations", rotations)
        object.__setattr__(self, "fps", float(self.fps))

    @property
    def horizon(self) -> int:
        """T, the number of target poses."""
        return len(self.positions)

    @property
    def poses(self) -> ToolPose:
        """The targets as tool poses (T, 3) and (T, 3, 3), world frame (what a scene replays)."""
        return ToolPose(self.positions, self.rotations)

    @classmethod
    def from_quaternions(cls, positions: np.ndarray, quaternions_wxyz: np.ndarray, fps: float) -> PoseTargets:
        """Targets from positions (T, 3) and scalar-first quaternions (T, 4), normalised here."""
        quaternions_wxyz = np.asarray(quaternions_wxyz, dtype=float)
        positions = np.asarray(positions, dtype=float)
        if quaternions_wxyz.ndim != 2 or quaternions_wxyz.shape[1] != 4:
            raise InputError(f"tip_quaternion_wxyz must have shape (T, 4), got {quaternions_wxyz.shape}")
        if len(quaternions_wxyz) != len(positions):
            raise InputError(
                f"tip_quaternion_wxyz has {len(quaternions_wxyz)} rows but tip_position has {len(positions)}"
            )
        norms = np.linalg.norm(quaternions_wxyz, axis=1)
        if not np.all(np.isfinite(norms) & (norms > 1e-9)):
            raise InputError("tip_quaternion_wxyz has zero or non-finite rows")
        w, x, y, z = (quaternions_wxyz / norms[:, None]).T
        rotations = np.stack(
            [
                np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
                np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
                np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
            ],
            axis=1,
        )
        return cls(positions, rotations, fps)

    def rotated_about_tool_z(self, angle: float) -> PoseTargets:
        """The same targets with every tool frame turned by ``angle`` (rad) about its own z axis
        (an equivalent target set for a roll-symmetric tool when angle = pi)."""
        c, s = np.cos(angle), np.sin(angle)
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return PoseTargets(self.positions, self.rotations @ turn, self.fps)


@dataclass(frozen=True)
class Linearisation:
    """Residuals and Jacobians of the pose term along a trajectory.

    Attributes:
        residuals: (T, 6) W log6(P_t^-1 M(q_t)), metres then radians (weighted).
        jacobians: (T, 6, 3 + N) d residual / d(base x, y, yaw, q_t), W Jlog6 J_LOCAL.
    """

    residuals: np.ndarray
    jacobians: np.ndarray


class TrackingProblem:
    """A robot, its targets and the cost; evaluates J, its terms and its linearisation.

    Args:
        robot: the robot holding its tool.
        targets: target poses P_1..P_T.
        dt: time between targets, seconds.
        q_start: (N,) joint configuration q_0 (fixed), radians; ``robot.q_neutral`` when None;
            clipped into the bound's range.
        weights: cost weights.
        bound: the joints' range, velocity and acceleration bounds (hard constraints);
            ``MotionBound.of(robot)`` when None, the bound the learning environment holds it to.
    """

    def __init__(
        self,
        robot: RobotModel,
        targets: PoseTargets,
        dt: float,
        q_start: np.ndarray | None = None,
        weights: TrackingWeights = TrackingWeights(),
        bound: MotionBound | None = None,
    ) -> None:
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be positive, got {dt}")
        q_start = robot.q_neutral if q_start is None else np.asarray(q_start, dtype=float)
        robot.check_configuration(q_start)
        self.robot = robot
        self.bound = MotionBound.of(robot) if bound is None else bound
        self.targets = targets
        self.dt = float(dt)
        # within the bound's range (the position margin: at most 0.01 rad from the model's limits)
        self.q_start = np.clip(q_start, self.bound.lower, self.bound.upper)
        self.weights = weights
        self._w = weights.pose_diagonal
        self._model = robot.full_model
        self._data = robot.full_model.createData()
        self._frame = robot.full_tool_frame_id
        self._targets_inverse = [pin.SE3(r, p).inverse() for p, r in zip(targets.positions, targets.rotations)]
        #: The terms of J, in the order their values and models are summed.
        self.terms: tuple[CostTerm, ...] = (
            PoseTerm(),
            VelocityTerm(weights.velocity),
            PostureTerm(weights.posture, self.q_start),
        )

    @property
    def horizon(self) -> int:
        return self.targets.horizon

    @property
    def n_joints(self) -> int:
        return self.robot.n_joints

    def pose_residuals(self, base: np.ndarray, q: np.ndarray) -> np.ndarray:
        """(T, 6) weighted pose residuals for base (3,) and trajectory q (T+1, N) (q_0 unused)."""
        errors = [self._error(base, q[t], t, jacobians=False) for t in range(1, self.horizon + 1)]
        return np.array([pin.log6(error).vector for error in errors]).reshape(self.horizon, 6) * self._w

    def linearise(self, base: np.ndarray, q: np.ndarray) -> Linearisation:
        """Residuals and Jacobians (see :class:`Linearisation`) at base (3,), trajectory (T+1, N)."""
        steps = [self.step_linearisation(base, q[t], t) for t in range(1, self.horizon + 1)]
        return Linearisation(np.array([r for r, _ in steps]), np.array([j for _, j in steps]))

    def step_linearisation(self, base: np.ndarray, q_t: np.ndarray, t: int) -> tuple[np.ndarray, np.ndarray]:
        """Residual (6,) and Jacobian (6, 3 + N) of target t (1..T) at base (3,) and joints q_t (N,)."""
        error = self._error(base, q_t, t, jacobians=True)
        jacobian = pin.Jlog6(error) @ pin.getFrameJacobian(
            self._model, self._data, self._frame, pin.ReferenceFrame.LOCAL
        )
        return self._w * pin.log6(error).vector, self._w[:, None] * jacobian

    def _error(self, base: np.ndarray, q_t: np.ndarray, t: int, jacobians: bool) -> pin.SE3:
        """P_t^-1 M(base, q_t), the tool frame relative to target t (1..T); with ``jacobians`` the
        joint Jacobians are computed too (for ``getFrameJacobian``)."""
        q_full = np.concatenate([base, q_t])
        if jacobians:
            pin.computeJointJacobians(self._model, self._data, q_full)
        else:
            pin.forwardKinematics(self._model, self._data, q_full)
        return self._targets_inverse[t - 1] * pin.updateFramePlacement(self._model, self._data, self._frame)

    def point(self, base: np.ndarray, q: np.ndarray) -> Point:
        """J's evaluation point at base (3,) and trajectory q (T+1, N)."""
        return Point(base, q, self.dt, self.pose_residuals(base, q))

    def iterate(self, base: np.ndarray, q: np.ndarray, base_columns: np.ndarray) -> Iterate:
        """The SQP's linearisation point, with Jacobians in the active base coordinates ``base_columns``."""
        lin = self.linearise(base, q)
        return Iterate(base, q, self.dt, lin.residuals, lin.jacobians[:, :, base_columns], lin.jacobians[:, :, 3:])

    def cost_terms(self, base: np.ndarray, q: np.ndarray) -> dict[str, float]:
        """J's terms (``pose``, ``velocity``, ``posture``) and their sum ``total`` for base (3,),
        q (T+1, N)."""
        at = self.point(base, q)
        terms = {term.name: term.value(at) for term in self.terms}
        return terms | {"total": sum(terms.values())}

    def cost(self, base: np.ndarray, q: np.ndarray) -> float:
        """J at base (3,) and trajectory q (T+1, N)."""
        return self.cost_terms(base, q)["total"]
