"""The benchmark's model, targets and guesses match the numbers written in PROBLEM.md."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from toolimit.robots import make_robot

# PROBLEM.md, "Robot model"
TOOL_R = np.array([[0.707107, -0.353553, 0.612372], [-0.707107, -0.353553, 0.612372], [0.0, -0.866025, -0.5]])
TOOL_P = np.array([0.282843, 0.282843, 0.062])
LOWER = np.array([-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973])
UPPER = np.array([2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973])
VLIM = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
TIP0 = np.array([0.306885, -0.4, 0.635276])


def test_tool_frame_placement_relative_to_joint7(panda_on_base):
    frame = panda_on_base.model.frames[panda_on_base.tool_frame_id]
    assert panda_on_base.model.names[frame.parentJoint] == "panda_joint7"
    np.testing.assert_allclose(frame.placement.rotation, TOOL_R, atol=1e-6)
    np.testing.assert_allclose(frame.placement.translation, TOOL_P, atol=1e-6)


def test_layout_and_limits(panda_on_base):
    assert panda_on_base.model.nq == panda_on_base.model.nv == 10
    assert panda_on_base.joint_names[:3] == ("base_x", "base_y", "base_yaw")
    np.testing.assert_allclose(panda_on_base.lower, LOWER)
    np.testing.assert_allclose(panda_on_base.upper, UPPER)
    np.testing.assert_allclose(panda_on_base.velocity_limit, VLIM)


def test_tip_at_neutral_pose(trajopt_problem, panda_on_base):
    q = np.concatenate([np.zeros(3), trajopt_problem.Q0_ARM])
    np.testing.assert_allclose(trajopt_problem.tool_pose(panda_on_base, q).translation, TIP0, atol=1e-6)


def test_base_moves_the_tip_rigidly(trajopt_problem, panda_on_base):
    """The base is (x, y, yaw) on the floor: moving it moves the tip by the same planar transform."""
    q_arm = trajopt_problem.Q0_ARM
    base = np.array([0.3, -0.2, 0.7])
    moved = trajopt_problem.tool_pose(panda_on_base, np.concatenate([base, q_arm]))
    at_origin = trajopt_problem.tool_pose(panda_on_base, np.concatenate([np.zeros(3), q_arm]))
    planar = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, base[2]), np.array([base[0], base[1], 0.0]))
    assert moved.isApprox(planar * at_origin, 1e-12)


def test_toolimit_robot_has_the_same_kinematics(trajopt_problem, panda_on_base):
    """toolimit's make_robot with PROBLEM.md's tool placement gives the same world tool pose."""
    link8 = panda_on_base.model.frames[panda_on_base.model.getFrameId("panda_link8")].placement
    robot = make_robot("panda", tool="spade", tool_placement=link8 * trajopt_problem.tool_placement(), base_height=0.0)
    rng = np.random.default_rng(0)
    for _ in range(5):
        q_arm = rng.uniform(panda_on_base.lower, panda_on_base.upper)
        base = rng.uniform([-1, -1, -np.pi], [1, 1, np.pi])
        expected = trajopt_problem.tool_pose(panda_on_base, np.concatenate([base, q_arm]))
        position, rotation = robot.tool_pose(q_arm, base)
        np.testing.assert_allclose(position, expected.translation, atol=1e-12)
        np.testing.assert_allclose(rotation, expected.rotation, atol=1e-12)


def test_targets_and_initial_guesses(trajopt_problem, panda_on_base, video_demos_dir):
    targets = trajopt_problem.load_targets(video_demos_dir / "spade_video1_aligned.npz")
    assert targets.positions.shape == (92, 3) and targets.rotations.shape == (92, 3, 3)
    np.testing.assert_allclose(np.einsum("tij,tik->tjk", targets.rotations, targets.rotations),
                               np.broadcast_to(np.eye(3), (92, 3, 3)), atol=1e-12)
    guesses = trajopt_problem.initial_base_guesses(panda_on_base, targets)
    centre = targets.positions[:, :2].mean(axis=0)
    assert guesses.shape == (8, 3)
    np.testing.assert_allclose(np.linalg.norm(guesses[:, :2] - centre, axis=1), 0.6)
    # guess 0 lies towards the world origin
    assert np.linalg.norm(guesses[0, :2]) == pytest.approx(np.linalg.norm(centre) - 0.6)
    # each yaw puts the q0 tip on the ray from the base towards the centre
    for guess in guesses:
        tip = trajopt_problem.tool_pose(panda_on_base, np.concatenate([guess, trajopt_problem.Q0_ARM])).translation
        to_tip, to_centre = tip[:2] - guess[:2], centre - guess[:2]
        assert to_tip[0] * to_centre[1] - to_tip[1] * to_centre[0] == pytest.approx(0.0, abs=1e-9)
        assert to_tip @ to_centre > 0


def test_bad_target_file_is_refused(trajopt_problem, tmp_path):
    path = tmp_path / "bad.npz"
    np.savez(path, tip_position=np.zeros((4, 3)), fps=24.0)
    with pytest.raises(ValueError, match="tip_quaternion_wxyz"):
        trajopt_problem.load_targets(path)


def _two_target_problem(trajopt_problem, panda_on_base, base, q_reachable):
    """Target 1: the tip pose at q_reachable (reachable); target 2: 3 m above the floor (out of reach)."""
    reachable = trajopt_problem.tool_pose(panda_on_base, np.concatenate([base, q_reachable]))
    positions = np.array([reachable.translation, [base[0], base[1], 3.0]])
    rotations = np.array([reachable.rotation, np.eye(3)])
    targets = trajopt_problem.Targets("two", positions, rotations, 24.0)
    return trajopt_problem.make_problem(panda_on_base, targets)


def test_metrics_of_a_crafted_trajectory(trajopt_problem, panda_on_base):
    base = np.array([0.1, 0.2, 0.3])
    q0_arm = trajopt_problem.Q0_ARM
    q_reachable = q0_arm + np.array([0.3, 0.2, -0.2, 0.3, 0.1, 0.2, -0.3])
    problem = _two_target_problem(trajopt_problem, panda_on_base, base, q_reachable)
    dt = problem.dt
    step1 = q0_arm + dt * np.array([2.175, 0, 0, 0, 0, 0, 0])  # joint 1 exactly at its velocity limit
    step2 = step1 + dt * np.array([0, 0, 0, 0, 0, 0, 2.7])  # joint 7 at 2.7 / 2.61 of its limit
    step2[3] = problem.upper[3] + 0.01  # and joint 4 (and its velocity) far beyond its limits
    q_trajectory = np.vstack([np.concatenate([[9.0, 9.0, 9.0], q0_arm]),  # q_0's base is only a guess
                              np.concatenate([base, step1]), np.concatenate([base, step2])])
    metrics = trajopt_problem.trajectory_metrics(problem, q_trajectory, with_static_ik=True)
    assert metrics["limit_violation_steps"] == 1
    assert metrics["limit_violation_max_rad"] == pytest.approx(0.01)
    assert metrics["steps_at_velocity_limit"] == 2
    assert metrics["velocity_violation_steps"] == 1
    assert metrics["cost_terms"]["joint_limits"] == pytest.approx(0.5 * 0.01**2)
    assert metrics["base"] == pytest.approx(base.tolist())
    # the static IK reaches target 1 (its pose comes from a configuration) but not target 2
    assert metrics["unreachable_steps_static_ik_position"] == 1
    assert metrics["unreachable_steps_static_ik_pose"] == 1
    assert metrics["position_error_per_step_m"][1] > 2.0
