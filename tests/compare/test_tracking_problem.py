"""The objective evaluator of PROBLEM.md (solver-independent)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from toolimit.compare import evaluate_cost


@pytest.fixture(scope="module")
def self_tracking(trajopt_problem, panda_on_base):
    """A 4-step trajectory and a problem whose targets are that trajectory's own tool poses."""
    base = np.array([0.2, -0.1, 1.0])
    q0_arm = trajopt_problem.Q0_ARM
    velocities = np.array([[0.5, -0.2, 0.1, 0.3, 0.0, -0.4, 1.0]] * 4) * np.array([[1], [2], [-1], [0.5]])
    arm = np.vstack([q0_arm, q0_arm + np.cumsum(velocities * trajopt_problem.DT, axis=0)])
    q_trajectory = np.hstack([np.tile(base, (5, 1)), arm])
    poses = [trajopt_problem.tool_pose(panda_on_base, q) for q in q_trajectory[1:]]
    positions, rotations = np.array([p.translation for p in poses]), np.array([p.rotation for p in poses])
    targets = trajopt_problem.Targets("self", positions, rotations, 24.0)
    return trajopt_problem.make_problem(panda_on_base, targets), q_trajectory, velocities


def test_cost_terms_by_hand(self_tracking):
    problem, q_trajectory, velocities = self_tracking
    terms = evaluate_cost(problem, q_trajectory)
    assert terms.pose == pytest.approx(0.0, abs=1e-20)
    assert terms.joint_limits == 0.0
    assert terms.velocity == pytest.approx(0.5 * 0.01 * np.sum(velocities**2), rel=1e-12)


def test_pose_term_is_weighted_log6(self_tracking):
    """Shift one target by 5 cm along its own x axis and turn it by 0.2 rad: J gains 1/2 (0.05^2 + (0.5*0.2)^2)."""
    problem, q_trajectory, _ = self_tracking
    rotations = problem.target_rotations.copy()
    positions = problem.target_positions.copy()
    offset = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, 0.2), np.array([0.05, 0.0, 0.0]))
    moved = pin.SE3(rotations[2], positions[2]) * offset
    rotations[2], positions[2] = moved.rotation, moved.translation
    shifted = dataclasses.replace(problem, target_positions=positions, target_rotations=rotations)
    expected = 0.5 * np.sum((np.array([1, 1, 1, 0.5, 0.5, 0.5]) * pin.log6(offset.inverse()).vector) ** 2)
    assert evaluate_cost(shifted, q_trajectory).pose == pytest.approx(expected, rel=1e-12)
    assert expected == pytest.approx(0.5 * (0.05**2 + 0.1**2), rel=0.05)


def test_limit_barrier(self_tracking):
    problem, q_trajectory, _ = self_tracking
    outside = q_trajectory.copy()
    outside[2:, 3 + 3] = problem.upper[3] + 0.1  # joint 4 above its limit on steps 2..4
    assert evaluate_cost(problem, outside).joint_limits == pytest.approx(3 * 0.5 * 0.1**2, rel=1e-9)


def test_rejects_a_moving_base_or_a_wrong_start(self_tracking):
    problem, q_trajectory, _ = self_tracking
    moving = q_trajectory.copy()
    moving[3, 0] += 1e-3
    with pytest.raises(ValueError, match="base moves"):
        evaluate_cost(problem, moving)
    wrong_start = q_trajectory.copy()
    wrong_start[0, 4] += 0.1
    with pytest.raises(ValueError, match=r"q_trajectory\[0\] arm"):
        evaluate_cost(problem, wrong_start)
    with pytest.raises(ValueError, match="shape"):
        evaluate_cost(problem, q_trajectory[:-1])
