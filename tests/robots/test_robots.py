"""Robot models: limits from the models, tool frame placement, FK and Jacobians vs finite differences."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from toolimit.errors import InputError
from toolimit.robots import ROBOTS, ArmDescription, arms, make_robot, register_robot, registry
from toolimit.tools import tool_spec


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    return make_robot(request.param, tool="spade")


def _random_configuration(robot, rng):
    return rng.uniform(robot.lower, robot.upper)


def test_registry_names_and_unknown_robot():
    assert set(ROBOTS) == {"planar3", "panda", "ur5", "talos"}
    with pytest.raises(ValueError, match="unknown robot 'kuka'.*panda"):
        make_robot("kuka")
    with pytest.raises(ValueError, match="unknown tool"):
        make_robot("panda", tool="rake")
    with pytest.raises(ValueError, match="tool_placement must be a pinocchio SE3"):
        make_robot("planar3", tool_placement=np.eye(4))


def test_limits_and_neutral_are_consistent(robot):
    n = robot.n_joints
    assert robot.lower.shape == robot.upper.shape == robot.velocity_limit.shape == robot.q_neutral.shape == (n,)
    assert len(robot.joint_names) == n
    assert np.all(robot.lower < robot.upper)
    assert np.all(robot.velocity_limit > 0) and np.all(np.isfinite(robot.velocity_limit))
    robot.check_configuration(robot.q_neutral)
    assert robot.full_model.nq == n + 3


def test_panda_limits_match_the_benchmark_problem():
    panda = make_robot("panda")
    np.testing.assert_allclose(panda.lower, [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973])
    np.testing.assert_allclose(panda.upper, [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973])
    np.testing.assert_allclose(panda.velocity_limit, [2.175] * 4 + [2.61] * 3)
    np.testing.assert_allclose(panda.q_neutral, [0, -0.785398, 0, -2.35619, 0, 1.5707, 0.785398], atol=1e-5)


def test_talos_is_torso_right_arm_and_tool_roll_as_the_authors_built_it():
    talos = make_robot("talos")
    arm = ("torso_1_joint", "torso_2_joint") + tuple(f"arm_right_{i}_joint" for i in range(1, 8))
    assert talos.joint_names == arm + ("tool_roll_joint",)
    np.testing.assert_allclose([talos.lower[-1], talos.upper[-1], talos.velocity_limit[-1]], [-6.14, 6.14, 2.61])
    # the pelvis 0.3 m above the scene's floor (the authors' get_default_robot_z)
    assert talos.base_height == pytest.approx(0.3)
    # the locked left arm and head do not move the tool; the right hand is on the right (-y)
    position, rotation = talos.tool_pose(talos.q_neutral, np.zeros(3))
    assert position[1] < -0.2
    # the tool roll turns the tool about its own axis: the head stays, the axis stays, x turns
    rolled = talos.q_neutral.copy()
    rolled[-1] = 1.0
    rolled_position, rolled_rotation = talos.tool_pose(rolled, np.zeros(3))
    np.testing.assert_allclose(rolled_position, position, atol=1e-12)
    np.testing.assert_allclose(rolled_rotation[:, 2], rotation[:, 2], atol=1e-12)
    assert rolled_rotation[:, 0] @ rotation[:, 0] == pytest.approx(np.cos(1.0))


def test_talos_without_the_tool_roll_is_the_gripper_held_tool():
    fixed, rolled = arms.talos(tool_roll=False), arms.talos()
    assert fixed.model.nq == rolled.model.nq - 1 == 9
    assert fixed.flange_frame == "gripper_right_base_link"
    data_fixed, data_rolled = fixed.model.createData(), rolled.model.createData()
    pin.framesForwardKinematics(fixed.model, data_fixed, fixed.q_neutral)
    pin.framesForwardKinematics(rolled.model, data_rolled, np.append(fixed.q_neutral, 0.0))
    gripper = data_fixed.oMf[fixed.model.getFrameId(fixed.flange_frame)]
    flange = data_rolled.oMf[rolled.model.getFrameId(rolled.flange_frame)]
    assert gripper.isApprox(flange, 1e-12)  # at roll 0 the flange is the gripper


def test_tool_head_is_tool_length_from_the_flange_along_the_approach_axis(robot):
    rng = np.random.default_rng(0)
    length = tool_spec("spade").length
    data = robot.model.createData()
    flange_id = robot.model.getFrameId(robot.flange_frame)
    for _ in range(3):
        q = _random_configuration(robot, rng)
        pin.framesForwardKinematics(robot.model, data, q)
        flange, tool = data.oMf[flange_id], data.oMf[robot.tool_frame_id]
        offset = flange.translation - tool.translation  # head -> handle end (at the flange)
        assert np.linalg.norm(offset) == pytest.approx(length, abs=1e-9)
        np.testing.assert_allclose(tool.rotation[:, 2], offset / length, atol=1e-9)  # tool z towards the handle


def test_tool_placement_override_is_relative_to_the_flange_parent_joint():
    placement = pin.SE3(pin.rpy.rpyToMatrix(0.1, 0.2, 0.3), np.array([0.01, 0.02, 0.5]))
    panda = make_robot("panda", tool_placement=placement)
    data = panda.model.createData()
    q = panda.q_neutral
    pin.framesForwardKinematics(panda.model, data, q)
    joint7 = data.oMi[panda.model.getJointId("panda_joint7")]
    expected = joint7 * placement
    np.testing.assert_allclose(data.oMf[panda.tool_frame_id].homogeneous, expected.homogeneous, atol=1e-12)


@pytest.mark.parametrize(
    "name, tool, height",
    [("panda", "spade", -0.2), ("panda", "hammer", 0.0), ("panda", "scythe", 0.0), ("ur5", "spade", 0.0),
     ("ur5", "hammer", 0.0), ("talos", "spade", 0.3)],
)
def test_base_heights_are_the_authors_per_robot_and_tool(name, tool, height):
    """method/utils.py get_default_robot_z: the spade scene 0.2 m above the Panda's base, the UR5 on
    the floor, Talos's pelvis 0.3 m above it; the tool rises with the base."""
    robot = make_robot(name, tool=tool)
    assert robot.base_height == pytest.approx(height)
    on_floor = make_robot(name, tool=tool, base_height=0.0)
    q = robot.q_neutral
    np.testing.assert_allclose(robot.tool_pose(q, np.zeros(3))[0], on_floor.tool_pose(q, np.zeros(3))[0] + [0, 0, height],
                               atol=1e-12)


def test_base_moves_the_tool_rigidly_and_base_height_lifts_it(robot):
    rng = np.random.default_rng(1)
    q = _random_configuration(robot, rng)
    p0, r0 = robot.tool_pose(q, np.zeros(3))
    base = np.array([0.3, -0.2, 0.7])
    p1, r1 = robot.tool_pose(q, base)
    yaw = pin.rpy.rpyToMatrix(0, 0, 0.7)
    np.testing.assert_allclose(p1, yaw @ p0 + [0.3, -0.2, 0.0], atol=1e-12)
    np.testing.assert_allclose(r1, yaw @ r0, atol=1e-12)
    lifted = make_robot(robot.name, base_height=robot.base_height + 0.25)
    np.testing.assert_allclose(lifted.tool_pose(q, np.zeros(3))[0], p0 + [0, 0, 0.25], atol=1e-12)


def test_planar3_moves_in_the_xz_plane():
    arm = make_robot("planar3")
    assert arm.base_dofs.tolist() == [True, False, False]
    rng = np.random.default_rng(2)
    for _ in range(5):
        position, rotation = arm.tool_pose(_random_configuration(arm, rng), np.array([0.4, 0.0, 0.0]))
        assert position[1] == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(np.abs(rotation[:, 1]), [0, 1, 0], atol=1e-12)  # tool y = -+ world y


@pytest.mark.parametrize("reference", ["local", "world_aligned"])
def test_tool_jacobian_matches_finite_differences(robot, reference):
    rng = np.random.default_rng(3)
    q = _random_configuration(robot, rng)
    base = np.array([0.2, -0.1, 0.4])
    jacobian = robot.tool_jacobian(q, base, reference)
    placement = robot.tool_placement_world(q, base)
    eps = 1e-6
    numeric = np.zeros_like(jacobian)
    for i in range(3 + robot.n_joints):
        delta = np.zeros(3 + robot.n_joints)
        delta[i] = eps
        moved = robot.tool_placement_world(q + delta[3:], base + delta[:3])
        if reference == "local":
            numeric[:, i] = pin.log6(placement.inverse() * moved).vector / eps
        else:
            numeric[:3, i] = (moved.translation - placement.translation) / eps
            numeric[3:, i] = pin.log3(moved.rotation @ placement.rotation.T) / eps
    np.testing.assert_allclose(jacobian, numeric, atol=1e-5)
    with pytest.raises(ValueError, match="reference"):
        robot.tool_jacobian(q, base, "world")


def test_check_configuration_names_the_joint():
    panda = make_robot("panda")
    q = panda.q_neutral.copy()
    q[3] = 0.5
    with pytest.raises(ValueError, match="panda_joint4"):
        panda.check_configuration(q)


@pytest.fixture
def fresh_registry(monkeypatch):
    """The robot registry as it is, restored after the test."""
    monkeypatch.setattr(registry, "_BUILDERS", dict(registry._BUILDERS))


def test_a_registered_robot_is_built_and_listed(fresh_registry):
    def small() -> ArmDescription:
        return dataclasses.replace(arms.planar3(), name="small")

    register_robot("small", small)
    assert "small" in ROBOTS and list(ROBOTS)[-1] == "small"  # ROBOTS follows the registry
    assert make_robot("small", tool="hammer").name == "small"


def test_bad_registrations_are_one_input_error(fresh_registry):
    with pytest.raises(InputError, match="robot 'panda' is already registered"):
        register_robot("panda", arms.panda)
    with pytest.raises(InputError, match="robot 'arm': the builder must be callable"):
        register_robot("arm", "toolimit.robots.arms:panda")
    register_robot("renamed", arms.planar3)
    with pytest.raises(InputError, match="robot 'renamed': its builder's ArmDescription is named 'planar3'"):
        make_robot("renamed")
