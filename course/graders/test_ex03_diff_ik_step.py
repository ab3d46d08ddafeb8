"""Grader of exercise 03: one differential-IK QP step, checked against an OSQP solution computed here
with the library's tool placement and LOCAL Jacobian (``toolimit.robots``).

Each case comes from a seeded generator: the message names the seed, the case, what was expected
(rad/s) and which constraints bind in the expected answer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import osqp
import pinocchio as pin
import pytest
import scipy.sparse as sp
from grading import case_seeds, check, fmt, fmt_shape

from toolimit.robots import RobotModel, make_robot

MODULE = "ex03_diff_ik_step"
#: Existing implementations of this exercise (the library's trajectory optimisation solves the same
#: QP over a horizon): a submission calling one of them gets 0 (grading.py).
#: Points of each test group (all its cases share them): 10 for the exercise.
WEIGHTS = {
    "test_ex03_matches_reference_small_steps": 3.5,
    "test_ex03_matches_reference_at_velocity_limits": 2.5,
    "test_ex03_matches_reference_at_position_limits": 2.5,
    "test_ex03_respects_the_limits": 1,
    "test_ex03_zero_error_gives_zero_velocity": 0.5,
}
#: What each function returns, for the message on a value the checks cannot read.
RETURNS = {"diff_ik_step": "a (N,) float array, the joint velocities in rad/s"}
#: Imported in the student's process before their module (it may start no thread afterwards).
STUDENT_IMPORTS = ["numpy", "scipy.sparse", "osqp", "pinocchio", "toolimit.robots"]
FORBIDDEN = ["toolimit.trajopt", "toolimit.compare"]
VELOCITY_TOLERANCE = 1e-4  # rad/s between your answer and the expected one
CONSTRAINT_TOLERANCE = 1e-6  # rad/s (velocity limits) and rad (position limits)


@pytest.fixture(scope="module")
def panda() -> RobotModel:
    return make_robot("panda")


@dataclass(frozen=True)
class Case:
    """One step: q (N,) rad, target (world frame), dt s, weights, base (x, y, yaw)."""

    description: str
    q: np.ndarray
    target_position: np.ndarray
    target_rotation: np.ndarray
    dt: float
    pose_weights: np.ndarray
    velocity_weight: float
    base: np.ndarray

    def call(self, function):
        return function(
            self.q.copy(),
            self.target_position.copy(),
            self.target_rotation.copy(),
            self.dt,
            self.pose_weights.copy(),
            self.velocity_weight,
            self.base.copy(),
        )


def make_case(robot: RobotModel, seed: int, kind: str) -> Case:
    """``small``: a target a few hundredths of a radian away (no constraint binds);
    ``fast``: a target far away at dt = 0.04 s (velocity limits bind);
    ``at_limit``: one joint 5 mrad from its lower limit, the target beyond it (its position limit binds)."""
    rng = np.random.default_rng(seed)
    margin = 0.3
    q = rng.uniform(robot.lower + margin, robot.upper - margin)
    base = np.array([rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-np.pi, np.pi)])
    pose_weights = np.repeat([rng.uniform(0.5, 2.0), rng.uniform(0.2, 1.0)], 3)
    velocity_weight = float(10 ** rng.uniform(-4, -2))
    if kind == "small":
        dt = float(rng.uniform(0.02, 0.1))
        q_target = q + rng.normal(0.0, 0.03, q.shape)
    elif kind == "fast":
        dt = 0.04
        q_target = q + rng.normal(0.0, 0.5, q.shape)
    elif kind == "at_limit":
        dt = 0.1
        joint = int(rng.integers(len(q)))
        q[joint] = robot.lower[joint] + 0.005
        q_target = q + rng.normal(0.0, 0.01, q.shape)
        q_target[joint] = robot.lower[joint] - 0.3
    else:
        raise ValueError(kind)
    position, rotation = robot.tool_pose(q_target, base)
    description = f"seed {seed}, {kind} case, dt {dt:.3f} s, w_v {velocity_weight:.3g}, W {fmt(pose_weights, 3)}"
    return Case(description, q, position, rotation, dt, pose_weights, velocity_weight, base)


def bounds(robot: RobotModel, case: Case) -> tuple[np.ndarray, np.ndarray]:
    """Velocity bounds (rad/s) combining the velocity limits and the position limits over dt."""
    lower = np.maximum(-robot.velocity_limit, (robot.lower - case.q) / case.dt)
    upper = np.minimum(robot.velocity_limit, (robot.upper - case.q) / case.dt)
    return lower, upper


def expected_velocity(robot: RobotModel, case: Case) -> np.ndarray:
    """The QP of the exercise with the library's placement and LOCAL Jacobian, solved by OSQP."""
    current = robot.tool_placement_world(case.q, case.base)
    error = pin.log6(current.actInv(pin.SE3(case.target_rotation, case.target_position))).vector
    jacobian = robot.tool_jacobian(case.q, case.base, reference="local")[:, 3:]
    weighted = case.pose_weights[:, None] * jacobian * case.dt
    n = len(case.q)
    hessian = sp.csc_matrix(2.0 * (weighted.T @ weighted + case.velocity_weight * np.eye(n)))
    gradient = -2.0 * weighted.T @ (case.pose_weights * error)
    lower, upper = bounds(robot, case)
    solver = osqp.OSQP()
    solver.setup(
        hessian,
        gradient,
        sp.identity(n, format="csc"),
        lower,
        upper,
        eps_abs=1e-10,
        eps_rel=1e-10,
        polishing=True,
        verbose=False,
        max_iter=200000,
    )
    result = solver.solve(raise_error=False)
    assert result.info.status_val == osqp.SolverStatus.OSQP_SOLVED, f"grader's QP failed: {result.info.status}"
    return np.clip(result.x, lower, upper)


def binding_constraints(robot: RobotModel, case: Case, v: np.ndarray) -> str:
    velocity = [robot.joint_names[j] for j in range(len(v)) if abs(abs(v[j]) - robot.velocity_limit[j]) < 1e-6]
    q_next = case.q + v * case.dt
    position = [
        robot.joint_names[j]
        for j in range(len(v))
        if min(q_next[j] - robot.lower[j], robot.upper[j] - q_next[j]) < 1e-6
    ]
    return (
        f"in the expected answer, joints at their velocity limit: {velocity or 'none'}; "
        f"at a position limit after the step: {position or 'none'}"
    )


def student_velocity(submission, robot: RobotModel, case: Case) -> np.ndarray:
    answer = case.call(lambda *args: submission(MODULE).diff_ik_step(robot, *args))
    got = np.asarray(answer, dtype=float)
    check(
        got.shape == (robot.n_joints,),
        f"{case.description}: expected shape ({robot.n_joints},), got {fmt_shape(answer)}",
    )
    check(np.all(np.isfinite(got)), f"{case.description}: your velocity has non-finite entries: {fmt(got)} rad/s")
    return got


def check_against_reference(submission, robot: RobotModel, case: Case) -> None:
    expected = expected_velocity(robot, case)
    got = student_velocity(submission, robot, case)
    gap = np.abs(got - expected)
    worst = int(np.argmax(gap))
    check(
        gap.max() <= VELOCITY_TOLERANCE,
        lambda: (
            f"{case.description}, q = {fmt(case.q, 4)} rad:\n  expected v = {fmt(expected)} rad/s\n"
            f"  you gave  v = {fmt(got)} rad/s\n"
            f"  largest gap {gap[worst]:.3g} rad/s at {robot.joint_names[worst]};\n"
            f"  {binding_constraints(robot, case, expected)}"
        ),
    )


@pytest.mark.parametrize("seed", case_seeds(4))
def test_ex03_matches_reference_small_steps(submission, panda, seed):
    """No constraint binds: checks the error, the LOCAL Jacobian, dt and the weights."""
    check_against_reference(submission, panda, make_case(panda, seed, "small"))


@pytest.mark.parametrize("seed", case_seeds(3, 10))
def test_ex03_matches_reference_at_velocity_limits(submission, panda, seed):
    check_against_reference(submission, panda, make_case(panda, seed, "fast"))


@pytest.mark.parametrize("seed", case_seeds(3, 20))
def test_ex03_matches_reference_at_position_limits(submission, panda, seed):
    check_against_reference(submission, panda, make_case(panda, seed, "at_limit"))


@pytest.mark.parametrize("kind", ["fast", "at_limit"])
def test_ex03_respects_the_limits(submission, panda, kind):
    for seed in case_seeds(4, 30):
        case = make_case(panda, seed, kind)
        got = student_velocity(submission, panda, case)
        excess = np.abs(got) - panda.velocity_limit
        joint = int(np.argmax(excess))
        check(
            excess.max() <= CONSTRAINT_TOLERANCE,
            f"{case.description}: |v| = {abs(got[joint]):.5g} rad/s at {panda.joint_names[joint]} exceeds its "
            f"velocity limit {panda.velocity_limit[joint]:.5g} rad/s by {excess.max():.3g} rad/s",
        )
        q_next = case.q + got * case.dt
        outside = np.maximum(panda.lower - q_next, q_next - panda.upper)
        joint = int(np.argmax(outside))
        check(
            outside.max() <= CONSTRAINT_TOLERANCE,
            f"{case.description}: q + v dt = {q_next[joint]:.5g} rad leaves the limits "
            f"[{panda.lower[joint]:.5g}, {panda.upper[joint]:.5g}] rad of {panda.joint_names[joint]} "
            f"by {outside.max():.3g} rad",
        )


def test_ex03_zero_error_gives_zero_velocity(submission, panda):
    q = panda.q_neutral
    position, rotation = panda.tool_pose(q, np.zeros(3))
    case = Case("target = current tool pose", q, position, rotation, 0.05, np.ones(6), 1e-3, np.zeros(3))
    got = student_velocity(submission, panda, case)
    check(
        np.abs(got).max() <= VELOCITY_TOLERANCE,
        f"{case.description} (q = {fmt(q, 4)} rad): expected v = 0, got {fmt(got)} rad/s",
    )
