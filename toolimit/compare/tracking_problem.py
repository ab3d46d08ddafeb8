"""A tool-pose tracking problem with a free mobile base, and its objective evaluated from a trajectory.

The problem (benchmarks/trajopt PROBLEM.md): a robot whose configuration is
``q = [b (n_base), qa (n_arm)]`` where the base ``b`` (e.g. x, y, yaw in metres/radians) is the
first joints of the Pinocchio model (Euclidean, ``nq == nv``), and the arm follows
``qa_t = qa_{t-1} + dt v_t``. Given target poses ``P_1..P_T`` of a tool frame (world frame),

    J = sum_{t=1..T} 1/2 |W log6(P_t^-1 M(q_t))|^2 + 1/2 w_lim |qa_t - clip(qa_t, lb, ub)|^2
                     + 1/2 w_v |v_t|^2

with ``log6`` Pinocchio's (linear part first, error in the tool's local frame). The objective is
computed here from the configurations alone, so that any solver's answer is scored the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

_BASE_CONSTANT_TOL = 1e-9  # metres/radians: the base must not move after q_0


@dataclass(frozen=True)
class BaseTrackingProblem:
    """Everything that defines the tracking problem (arrays are float64, world frame, SI units).

    Attributes:
        model: Pinocchio model, ``nq == nv``; joints ``0..n_base-1`` of q are the base.
        frame_id: the tracked tool frame.
        target_positions: (T, 3) target tool-frame origins P_t.translation, metres, world frame.
        target_rotations: (T, 3, 3) target tool-frame orientations P_t.rotation, world frame.
        q0: (nq,) initial configuration; its arm part is fixed, its base part is only a guess.
        dt: time step between targets, seconds.
        pose_weights: (6,) diagonal of W applied to log6 (linear [m] then angular [rad] part).
        w_v: weight on the arm joint velocities (rad/s) squared.
        w_lim: weight of the quadratic barrier outside the arm joint limits (rad) squared.
        lower, upper: (n_arm,) arm joint position limits, radians.
        velocity_limit: (n_arm,) arm joint velocity limits, rad/s (hard box on v).
        n_base: number of base coordinates at the start of q.
    """

    model: pin.Model
    frame_id: int
    target_positions: np.ndarray
    target_rotations: np.ndarray
    q0: np.ndarray
    dt: float
    pose_weights: np.ndarray
    w_v: float
    w_lim: float
    lower: np.ndarray
    upper: np.ndarray
    velocity_limit: np.ndarray
    n_base: int = 3

    def __post_init__(self) -> None:
        nq, nv = self.model.nq, self.model.nv
        if nq != nv:
            raise ValueError(f"model must be Euclidean (nq == nv), got nq={nq}, nv={nv}")
        n_arm = nq - self.n_base
        horizon = len(self.target_positions)
        expected = {
            "target_positions": (horizon, 3),
            "target_rotations": (horizon, 3, 3),
            "q0": (nq,),
            "pose_weights": (6,),
            "lower": (n_arm,),
            "upper": (n_arm,),
            "velocity_limit": (n_arm,),
        }
        for name, shape in expected.items():
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != shape:
                raise ValueError(f"{name} must have shape {shape}, got {value.shape}")
            if not np.all(np.isfinite(value)):
                raise ValueError(f"{name} contains non-finite values")
            object.__setattr__(self, name, value)
        if horizon < 1:
            raise ValueError("at least one target pose is needed")
        if not self.dt > 0:
            raise ValueError(f"dt must be positive, got {self.dt}")
        if not 0 <= self.frame_id < len(self.model.frames):
            raise ValueError(f"frame_id {self.frame_id} is not a frame of the model")

    @property
    def horizon(self) -> int:
        """T, the number of targets and of velocity steps."""
        return len(self.target_positions)

    @property
    def n_arm(self) -> int:
        return self.model.nq - self.n_base

    def target(self, t: int) -> pin.SE3:
        """P_t for t = 1..T (world frame)."""
        return pin.SE3(self.target_rotations[t - 1], self.target_positions[t - 1])

    def limit_excess(self, q_arm: np.ndarray) -> np.ndarray:
        """qa - clip(qa, lb, ub): how far each arm joint is outside its limits, radians (signed)."""
        return q_arm - np.clip(q_arm, self.lower, self.upper)


def pose_residual(problem: BaseTrackingProblem, data: pin.Data, q: np.ndarray, target: pin.SE3) -> np.ndarray:
    """W log6(P^-1 M(q)) (6,): weighted tool-pose error in the tool's local frame (m, rad)."""
    pin.framesForwardKinematics(problem.model, data, q)
    error = target.actInv(data.oMf[problem.frame_id])
    return problem.pose_weights * pin.log6(error).vector


def pose_residual_and_jacobian(
    problem: BaseTrackingProblem, data: pin.Data, q: np.ndarray, target: pin.SE3
) -> tuple[np.ndarray, np.ndarray]:
    """The residual W log6(P^-1 M(q)) (6,) and its Jacobian W Jlog6 J_LOCAL(q) (6, nv)."""
    model = problem.model
    pin.computeJointJacobians(model, data, q)  # also runs forward kinematics
    pin.updateFramePlacements(model, data)
    error = target.actInv(data.oMf[problem.frame_id])
    residual = problem.pose_weights * pin.log6(error).vector
    frame_jacobian = pin.getFrameJacobian(model, data, problem.frame_id, pin.ReferenceFrame.LOCAL)
    jacobian = problem.pose_weights[:, None] * (pin.Jlog6(error) @ frame_jacobian)
    return residual, jacobian


@dataclass(frozen=True)
class CostTerms:
    """The objective J split into its terms (dimensionless, each already halved)."""

    pose: float
    velocity: float
    joint_limits: float

    @property
    def total(self) -> float:
        return self.pose + self.velocity + self.joint_limits

    def as_dict(self) -> dict[str, float]:
        return {"pose": self.pose, "velocity": self.velocity, "joint_limits": self.joint_limits}


def check_trajectory(problem: BaseTrackingProblem, q_trajectory: np.ndarray) -> np.ndarray:
    """Validate a (T+1, nq) trajectory: its arm starts at q0's and its base is constant over q_1..q_T.

    The base part of q_0 enters no cost (it is only the solver's initial guess), so it is not checked.
    """
    q_trajectory = np.asarray(q_trajectory, dtype=float)
    expected = (problem.horizon + 1, problem.model.nq)
    if q_trajectory.shape != expected:
        raise ValueError(f"q_trajectory must have shape {expected}, got {q_trajectory.shape}")
    if not np.all(np.isfinite(q_trajectory)):
        raise ValueError("q_trajectory contains non-finite values")
    arm_start_error = np.max(np.abs(q_trajectory[0, problem.n_base :] - problem.q0[problem.n_base :]))
    if arm_start_error > _BASE_CONSTANT_TOL:
        raise ValueError(f"q_trajectory[0] arm differs from the problem's q0 by {arm_start_error:.3g} rad")
    bases = q_trajectory[1:, : problem.n_base]
    base_drift = np.max(np.abs(bases - bases[0]))
    if base_drift > _BASE_CONSTANT_TOL:
        raise ValueError(f"the base moves along q_trajectory[1:] (by up to {base_drift:.3g}); it must be constant")
    return q_trajectory


def arm_velocities(problem: BaseTrackingProblem, q_trajectory: np.ndarray) -> np.ndarray:
    """v_t = (qa_t - qa_{t-1}) / dt, t = 1..T: (T, n_arm) arm joint velocities, rad/s."""
    q_trajectory = check_trajectory(problem, q_trajectory)
    return np.diff(q_trajectory[:, problem.n_base :], axis=0) / problem.dt


def evaluate_cost(problem: BaseTrackingProblem, q_trajectory: np.ndarray) -> CostTerms:
    """J of a (T+1, nq) trajectory ``[q_0, ..., q_T]``, velocities taken from its differences."""
    q_trajectory = check_trajectory(problem, q_trajectory)
    velocities = arm_velocities(problem, q_trajectory)
    data = problem.model.createData()
    pose = 0.0
    limits = 0.0
    for t in range(1, problem.horizon + 1):
        residual = pose_residual(problem, data, q_trajectory[t], problem.target(t))
        pose += 0.5 * float(residual @ residual)
        excess = problem.limit_excess(q_trajectory[t, problem.n_base :])
        limits += 0.5 * problem.w_lim * float(excess @ excess)
    velocity = 0.5 * problem.w_v * float(np.sum(velocities**2))
    return CostTerms(pose=pose, velocity=velocity, joint_limits=limits)
