"""The reference problem of ../shared/benchmarks/trajopt/PROBLEM.md: model, targets, guesses, metrics.

Panda (example-robot-data, fingers locked) carrying a spade whose tip frame ``spade_tip`` is
tracked, mounted on a planar base ``[bx, by, byaw]`` (PX, PY, RZ joints at the world origin, so the
base stands on the floor z = 0). Configuration layout ``q = [bx, by, byaw, q1..q7]`` (m, m, rad,
rad...). Both solvers of the benchmark (toolimit's sequential QP and Crocoddyl) are scored here
with the same functions.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import example_robot_data
import numpy as np
import pinocchio as pin
from scipy.optimize import least_squares

from toolimit.compare import BaseTrackingProblem, evaluate_cost
from toolimit.compare.tracking_problem import arm_velocities, check_trajectory

TRAJECTORIES = ("spade_video1_aligned", "spade_example_aligned")
DT = 1.0 / 24.0  # s between targets
Q0_ARM = np.array([0.0, -0.785398, 0.0, -2.35619, 0.0, 1.5707, 0.785398])  # example-robot-data panda.q0
POSE_WEIGHTS = np.array([1.0, 1.0, 1.0, 0.5, 0.5, 0.5])  # W on log6 (linear, angular)
W_V = 0.01
W_LIM = 1.0
TOOL_FRAME = "spade_tip"
N_GUESSES = 8
GUESS_RADIUS = 0.6  # m from the targets' mean x-y
POSITION_TOLERANCE = 0.01  # m: "steps > 1 cm", static-IK reachability
LIMIT_TOLERANCE = 1e-6  # rad: a joint counts as outside its limits beyond this
VELOCITY_AT_LIMIT = 1.0 - 1e-3  # |v|/vlim from which a step counts as "at the velocity limit"
VELOCITY_TOLERANCE = 1e-6  # |v|/vlim - 1 beyond this is a velocity-limit violation
IK_MAX_EVALUATIONS = 100  # residual evaluations per static-IK start (a 1 cm decision needs no more)


def tool_placement() -> pin.SE3:
    """M_tool: the spade tip relative to panda_link8 (PROBLEM.md, rpy = Rz(y) Ry(p) Rx(r))."""
    mount = pin.SE3(pin.rpy.rpyToMatrix(-np.pi / 2, 0.0, -np.pi / 4), np.zeros(3))
    tip = pin.SE3(pin.rpy.rpyToMatrix(-np.pi / 6, 0.0, 0.0), np.array([0.0, 0.045, 0.40]))
    return mount * tip


@dataclass(frozen=True)
class PandaOnBase:
    """The PROBLEM.md model: ``model`` (nq = nv = 10), tool frame id, arm limits (rad, rad/s)."""

    model: pin.Model
    tool_frame_id: int
    lower: np.ndarray
    upper: np.ndarray
    velocity_limit: np.ndarray
    joint_names: tuple[str, ...]


def build_panda_on_base() -> PandaOnBase:
    """Panda with fingers locked, ``spade_tip`` on joint 7, appended to a PX-PY-RZ base at the origin."""
    robot = example_robot_data.load("panda")
    arm = pin.buildReducedModel(robot.model, [8, 9], robot.q0)
    link8 = arm.frames[arm.getFrameId("panda_link8")]
    arm.addFrame(
        pin.Frame(
            TOOL_FRAME,
            link8.parentJoint,
            arm.getFrameId("panda_link8"),
            link8.placement * tool_placement(),
            pin.FrameType.OP_FRAME,
        )
    )
    base = pin.Model()
    parent = 0
    base_joints = (("base_x", pin.JointModelPX()), ("base_y", pin.JointModelPY()), ("base_yaw", pin.JointModelRZ()))
    for name, joint in base_joints:
        parent = base.addJoint(parent, joint, pin.SE3.Identity(), name)
        base.appendBodyToJoint(parent, pin.Inertia.Zero(), pin.SE3.Identity())
    base_frame = base.addFrame(pin.Frame("base_link", parent, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    model = pin.appendModel(base, arm, base_frame, pin.SE3.Identity())
    if model.nq != 10 or model.nv != 10:
        raise RuntimeError(f"expected nq = nv = 10, got {model.nq}, {model.nv}")
    return PandaOnBase(
        model=model,
        tool_frame_id=model.getFrameId(TOOL_FRAME),
        lower=model.lowerPositionLimit[3:].copy(),
        upper=model.upperPositionLimit[3:].copy(),
        velocity_limit=model.velocityLimit[3:].copy(),
        joint_names=tuple(model.names[1:]),
    )


def tool_pose(robot: PandaOnBase, q: np.ndarray) -> pin.SE3:
    """oMf of ``spade_tip`` at q (10,), world frame."""
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.asarray(q, dtype=float))
    return pin.SE3(data.oMf[robot.tool_frame_id])


@dataclass(frozen=True)
class Targets:
    """Target tool-tip poses P_1..P_T (world frame): positions (T,3) m, rotations (T,3,3)."""

    name: str
    positions: np.ndarray
    rotations: np.ndarray
    fps: float


def load_targets(path: str | Path) -> Targets:
    """Read ``tip_position`` (T,3) and ``tip_quaternion_wxyz`` (T,4, normalised here) from a .npz."""
    path = Path(path)
    with np.load(path) as data:
        for key in ("tip_position", "tip_quaternion_wxyz", "fps"):
            if key not in data:
                raise ValueError(f"{path}: missing key {key!r}")
        positions = np.asarray(data["tip_position"], dtype=float)
        quaternions = np.asarray(data["tip_quaternion_wxyz"], dtype=float)
        fps = float(data["fps"])
    if positions.ndim != 2 or positions.shape[1] != 3 or quaternions.shape != (len(positions), 4):
        raise ValueError(f"{path}: tip_position {positions.shape} / tip_quaternion_wxyz {quaternions.shape} mismatch")
    quaternions = quaternions / np.linalg.norm(quaternions, axis=1, keepdims=True)
    rotations = np.array([pin.Quaternion(w, x, y, z).toRotationMatrix() for w, x, y, z in quaternions])
    return Targets(name=path.stem, positions=positions, rotations=rotations, fps=fps)


def make_problem(robot: PandaOnBase, targets: Targets, dt: float = DT, w_v: float = W_V) -> BaseTrackingProblem:
    """The OCP of PROBLEM.md (base part of q0 zero: it is only a guess, set per solve)."""
    return BaseTrackingProblem(
        model=robot.model,
        frame_id=robot.tool_frame_id,
        target_positions=targets.positions,
        target_rotations=targets.rotations,
        q0=np.concatenate([np.zeros(3), Q0_ARM]),
        dt=dt,
        pose_weights=POSE_WEIGHTS,
        w_v=w_v,
        w_lim=W_LIM,
        lower=robot.lower,
        upper=robot.upper,
        velocity_limit=robot.velocity_limit,
    )


def initial_base_guesses(robot: PandaOnBase, targets: Targets) -> np.ndarray:
    """(8, 3) base guesses [x, y, yaw]: 0.6 m around the targets' mean x-y, guess 0 towards the origin.

    The yaw puts the tip of the q0 pose on the ray from the base towards the centre.
    """
    centre = targets.positions[:, :2].mean(axis=0)
    tip0 = tool_pose(robot, np.concatenate([np.zeros(3), Q0_ARM])).translation
    first_angle = np.arctan2(-centre[1], -centre[0])
    guesses = []
    for k in range(N_GUESSES):
        angle = first_angle + 2.0 * np.pi * k / N_GUESSES
        position = centre + GUESS_RADIUS * np.array([np.cos(angle), np.sin(angle)])
        towards_centre = centre - position
        yaw = np.arctan2(towards_centre[1], towards_centre[0]) - np.arctan2(tip0[1], tip0[0])
        guesses.append([position[0], position[1], np.arctan2(np.sin(yaw), np.cos(yaw))])
    return np.array(guesses)


def _summary(values: np.ndarray) -> dict[str, float]:
    return {"mean": float(np.mean(values)), "median": float(np.median(values)), "max": float(np.max(values))}


def tracking_errors(problem: BaseTrackingProblem, q_trajectory: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per step t = 1..T: position error |p(q_t) - p_t| (m) and geodesic rotation error (rad)."""
    data = problem.model.createData()
    position_errors = np.empty(problem.horizon)
    rotation_errors = np.empty(problem.horizon)
    for t in range(1, problem.horizon + 1):
        pin.framesForwardKinematics(problem.model, data, q_trajectory[t])
        pose = data.oMf[problem.frame_id]
        position_errors[t - 1] = np.linalg.norm(pose.translation - problem.target_positions[t - 1])
        rotation_errors[t - 1] = np.linalg.norm(pin.log3(problem.target_rotations[t - 1].T @ pose.rotation))
    return position_errors, rotation_errors


def _static_ik_position_error(problem: BaseTrackingProblem, base: np.ndarray, t: int, starts: list[np.ndarray],
                              full_pose: bool) -> float:
    """Position error (m) left by a bounded least-squares IK of target t with the base fixed.

    ``full_pose``: minimise the OCP's weighted log6 residual; otherwise the position error only.
    The start with the lowest IK objective is kept. Arm joints are held in their hard limits
    (scipy's bounded "dogbox" least squares; "trf" needs ~10 times longer for the same counts).
    """
    model = problem.model
    data = model.createData()
    target = problem.target(t)
    n_base = problem.n_base

    def full(q_arm: np.ndarray) -> np.ndarray:
        return np.concatenate([base, q_arm])

    def residual(q_arm: np.ndarray) -> np.ndarray:
        pin.framesForwardKinematics(model, data, full(q_arm))
        pose = data.oMf[problem.frame_id]
        if full_pose:
            return problem.pose_weights * pin.log6(target.actInv(pose)).vector
        return pose.translation - target.translation

    def jacobian(q_arm: np.ndarray) -> np.ndarray:
        q = full(q_arm)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        pose = data.oMf[problem.frame_id]
        if full_pose:
            local = pin.getFrameJacobian(model, data, problem.frame_id, pin.ReferenceFrame.LOCAL)
            return (problem.pose_weights[:, None] * (pin.Jlog6(target.actInv(pose)) @ local))[:, n_base:]
        aligned = pin.getFrameJacobian(model, data, problem.frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        return aligned[:3, n_base:]

    margin = 1e-9  # least_squares needs a start strictly inside the bounds
    best_objective, best_position_error = np.inf, np.inf
    for start in starts:
        x0 = np.clip(start, problem.lower + margin, problem.upper - margin)
        result = least_squares(residual, x0, jac=jacobian, bounds=(problem.lower, problem.upper), method="dogbox",
                               xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=IK_MAX_EVALUATIONS)
        if result.cost < best_objective:
            best_objective = result.cost
            pin.framesForwardKinematics(model, data, full(result.x))
            best_position_error = float(np.linalg.norm(data.oMf[problem.frame_id].translation - target.translation))
    return best_position_error


def static_ik_unreachable_steps(problem: BaseTrackingProblem, q_trajectory: np.ndarray) -> dict[str, int]:
    """Steps whose target the arm cannot reach within 1 cm from the found base even statically."""
    base = q_trajectory[1, : problem.n_base]
    q0_arm = problem.q0[problem.n_base :]
    counts = {"unreachable_steps_static_ik_position": 0, "unreachable_steps_static_ik_pose": 0}
    for t in range(1, problem.horizon + 1):
        starts = [q_trajectory[t, problem.n_base :], q0_arm]
        if _static_ik_position_error(problem, base, t, starts, full_pose=False) > POSITION_TOLERANCE:
            counts["unreachable_steps_static_ik_position"] += 1
        if _static_ik_position_error(problem, base, t, starts, full_pose=True) > POSITION_TOLERANCE:
            counts["unreachable_steps_static_ik_pose"] += 1
    return counts


def trajectory_metrics(problem: BaseTrackingProblem, q_trajectory: np.ndarray, with_static_ik: bool = True) -> dict:
    """PROBLEM.md's metrics of a (T+1, 10) trajectory (q_0 included), J from :func:`evaluate_cost`."""
    q_trajectory = check_trajectory(problem, q_trajectory)
    terms = evaluate_cost(problem, q_trajectory)
    position_errors, rotation_errors = tracking_errors(problem, q_trajectory)
    arm = q_trajectory[1:, problem.n_base :]
    excess = np.abs(problem.limit_excess(arm))
    velocity_ratio = np.abs(arm_velocities(problem, q_trajectory)) / problem.velocity_limit
    step_ratio = velocity_ratio.max(axis=1)
    metrics = {
        "cost": terms.total,
        "cost_terms": terms.as_dict(),
        "base": q_trajectory[1, : problem.n_base].tolist(),
        "position_error_m": _summary(position_errors),
        "rotation_error_rad": _summary(rotation_errors),
        "steps_pos_err_gt_1cm": int(np.sum(position_errors > POSITION_TOLERANCE)),
        "limit_violation_steps": int(np.sum(excess.max(axis=1) > LIMIT_TOLERANCE)),
        "limit_violation_max_rad": float(excess.max()),
        "vel_ratio_max": float(step_ratio.max()),
        "steps_at_velocity_limit": int(np.sum(step_ratio >= VELOCITY_AT_LIMIT)),
        "velocity_violation_steps": int(np.sum(step_ratio > 1.0 + VELOCITY_TOLERANCE)),
        "position_error_per_step_m": position_errors.tolist(),
        "rotation_error_per_step_rad": rotation_errors.tolist(),
    }
    if with_static_ik:
        metrics.update(static_ik_unreachable_steps(problem, q_trajectory))
    return metrics
