"""The robot arms, each as an :class:`ArmDescription`: active joints, flange, rest pose, base height.

Mount frames (z = approach direction, along the held tool; see :mod:`toolimit.robots.model`):

* ``planar3``: a planar 3R arm built here. Revolute joints about world y, so the arm moves in the
  world x-z plane (at y = 0 for a zero base). Links of 0.40, 0.35 and 0.25 m along their local z:
  at q = 0 the arm points straight up, a positive angle leans it towards +x. Flange ``"flange"`` at
  the end of link 3, mount frame = flange frame (approach = link axis); the tool's x axis is the
  flange's x, in the x-z plane. Limits +-2.6 rad, 2.5 rad/s. Base: shoulder 0.5 m above the
  floor; only x moves (y and yaw fixed at 0, so the arm stays in its plane).
* ``panda``: example-robot-data's Panda, fingers locked (``pin.buildReducedModel``). Flange
  ``panda_link8`` (0.107 m beyond joint 7), approach = its z axis. Rest pose =
  example-robot-data's q0 (fingers dropped). Base on the floor (base_height 0, as in PROBLEM.md),
  except with the spade, whose scene stands 0.2 m above the base (base_height -0.2), as the
  authors placed it (``method/utils.py get_default_robot_z``: -0.2 for the Panda with the spade).
* ``ur5``: example-robot-data's UR5. Flange ``tool0``, approach = its z axis. Rest pose
  (0, -1.57, 1.57, -1.57, -1.57, 0) (elbow up, wrist pointing down). Base on the scene's floor
  (``get_default_robot_z``: 0).
* ``talos``: example-robot-data's full Talos reduced to its upper body as the authors built it
  (pyphysx_envs ``robot/talos_arm.py``): free-flyer, legs, left arm, head and both grippers locked
  at q0 (free-flyer at the origin); active: torso 1-2 (yaw, pitch), right arm 1-7 and a tool-roll
  joint ``tool_roll_joint`` (10 joints), a revolute joint about the approach axis at the gripper
  (+-6.14 rad, 2.61 rad/s: the authors' tenth joint). Flange ``tool_roll_link`` (the gripper's
  ``gripper_right_base_link`` turned by the tool roll), approach = its -z axis (towards the
  fingertips). Rest pose = q0's, tool roll 0. Base height 0.3 m: the pelvis 0.3 m above the
  scene's floor (the authors' ``method/utils.py get_default_robot_z``). The paper's text says the
  scene stands at Talos's knee height; the authors' code lowers the robot further (the pelvis at
  0.3 m, where the knee height of q0 would put it at 0.619 m), and the code is followed here.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from toolimit.robots.model import ArmDescription

#: planar3 link lengths (m), joint limit (rad), velocity limit (rad/s), shoulder height (m).
PLANAR3_LINKS = (0.40, 0.35, 0.25)
PLANAR3_JOINT_LIMIT = 2.6
PLANAR3_VELOCITY_LIMIT = 2.5
PLANAR3_BASE_HEIGHT = 0.5
#: The Panda's base with the spade: 0.2 m below the scene's floor (the authors' get_default_robot_z).
PANDA_SPADE_BASE_HEIGHT = -0.2
UR5_BASE_HEIGHT = 0.0
UR5_NEUTRAL = (0.0, -1.57, 1.57, -1.57, -1.57, 0.0)
#: Talos's pelvis above the scene's floor, m (the authors' ``get_default_robot_z``).
TALOS_BASE_HEIGHT = 0.3
TALOS_ACTIVE_JOINTS = ("torso_1_joint", "torso_2_joint") + tuple(f"arm_right_{i}_joint" for i in range(1, 8))
#: The tool-roll joint the authors add at Talos's gripper: its name, limit (rad), velocity (rad/s).
TALOS_TOOL_ROLL_JOINT = "tool_roll_joint"
TALOS_TOOL_ROLL_LIMIT = 6.14
TALOS_TOOL_ROLL_VELOCITY = 2.61
#: Talos's gripper frame, turned by the tool roll into the flange ``tool_roll_link``.
TALOS_GRIPPER_FRAME = "gripper_right_base_link"
#: Talos's approach axis in the gripper frame is its -z: the mount frame's rotation.
TALOS_MOUNT_ROTATION = np.diag([1.0, -1.0, -1.0])


def _load_example_robot(name: str):
    import example_robot_data

    return example_robot_data.load(name)


def planar3() -> ArmDescription:
    """The planar 3R arm (see the module docstring)."""
    model = pin.Model()
    model.name = "planar3"
    parent = 0
    offset = np.zeros(3)
    for i, length in enumerate(PLANAR3_LINKS, start=1):
        parent = model.addJoint(parent, pin.JointModelRY(), pin.SE3(np.eye(3), offset), f"joint{i}")
        # a slender rod of 1 kg along the link, for completeness (kinematics do not use it)
        inertia = pin.Inertia.FromCylinder(1.0, 0.02, length)
        inertia = pin.SE3(np.eye(3), np.array([0.0, 0.0, length / 2])).act(inertia)
        model.appendBodyToJoint(parent, inertia, pin.SE3.Identity())
        model.addBodyFrame(f"link{i}", parent, pin.SE3.Identity(), 0)
        offset = np.array([0.0, 0.0, length])
    model.addFrame(pin.Frame("flange", parent, pin.SE3(np.eye(3), offset), pin.FrameType.OP_FRAME))
    n = len(PLANAR3_LINKS)
    model.lowerPositionLimit = -PLANAR3_JOINT_LIMIT * np.ones(n)
    model.upperPositionLimit = PLANAR3_JOINT_LIMIT * np.ones(n)
    for limit in ("velocityLimit", "lowerVelocityLimit", "upperVelocityLimit"):
        setattr(model, limit, PLANAR3_VELOCITY_LIMIT * np.ones(n))
    return ArmDescription(
        name="planar3",
        model=model,
        flange_frame="flange",
        mount_rotation=np.eye(3),
        q_neutral=np.array([0.3, 1.2, 1.2]),
        base_height=PLANAR3_BASE_HEIGHT,
        base_dofs=(True, False, False),
    )


def _reduced(model: pin.Model, q_ref: np.ndarray, keep: tuple[str, ...]) -> pin.Model:
    """The model with every joint not in ``keep`` locked at ``q_ref``."""
    missing = [name for name in keep if not model.existJointName(name)]
    if missing:
        raise ValueError(f"{model.name}: no joints named {missing}")
    lock = [j for j in range(1, model.njoints) if model.names[j] not in keep]
    return pin.buildReducedModel(model, lock, q_ref)


def panda() -> ArmDescription:
    """example-robot-data's Panda with its two finger joints locked."""
    robot = _load_example_robot("panda")
    arm_joints = tuple(f"panda_joint{i}" for i in range(1, 8))
    model = _reduced(robot.model, robot.q0, arm_joints)
    return ArmDescription(
        name="panda",
        model=model,
        flange_frame="panda_link8",
        mount_rotation=np.eye(3),
        q_neutral=np.array(robot.q0[:7], dtype=float),
        base_height=0.0,
        tool_base_heights={"spade": PANDA_SPADE_BASE_HEIGHT},
    )


def ur5() -> ArmDescription:
    """example-robot-data's UR5, its base on the scene's floor."""
    robot = _load_example_robot("ur5")
    return ArmDescription(
        name="ur5",
        model=pin.Model(robot.model),
        flange_frame="tool0",
        mount_rotation=np.eye(3),
        q_neutral=np.array(UR5_NEUTRAL),
        base_height=UR5_BASE_HEIGHT,
    )


def talos(tool_roll: bool = True) -> ArmDescription:
    """Talos's upper body: torso (2) + right arm (7) + the authors' tool-roll joint (without it
    when ``tool_roll`` is False: 9 joints, the flange the gripper), everything else locked at q0."""
    robot = _load_example_robot("talos")
    q_ref = np.array(robot.q0, dtype=float)
    q_ref[:7] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]  # free-flyer at the origin (x, y, z, quaternion)
    model = _reduced(robot.model, q_ref, TALOS_ACTIVE_JOINTS)
    q_neutral = np.array(
        [robot.q0[robot.model.joints[robot.model.getJointId(name)].idx_q] for name in TALOS_ACTIVE_JOINTS]
    )
    flange = TALOS_GRIPPER_FRAME
    if tool_roll:
        flange = _add_tool_roll(model, TALOS_GRIPPER_FRAME, TALOS_MOUNT_ROTATION)
        q_neutral = np.append(q_neutral, 0.0)
    return ArmDescription(
        name="talos",
        model=model,
        flange_frame=flange,
        mount_rotation=TALOS_MOUNT_ROTATION,
        q_neutral=q_neutral,
        base_height=TALOS_BASE_HEIGHT,
    )


def _add_tool_roll(model: pin.Model, frame: str, mount_rotation: np.ndarray) -> str:
    """Append to ``model`` (in place) a revolute joint about the approach axis (the mount frame's z)
    at ``frame``, and a frame ``tool_roll_link`` on it placed as ``frame`` at roll 0; its name."""
    parent = model.frames[model.getFrameId(frame)]
    mount = pin.SE3(np.asarray(mount_rotation, dtype=float), np.zeros(3))
    joint = model.addJoint(
        parent.parentJoint,
        pin.JointModelRZ(),
        parent.placement * mount,
        TALOS_TOOL_ROLL_JOINT,
        np.array([1.0]),
        np.array([TALOS_TOOL_ROLL_VELOCITY]),
        np.array([-TALOS_TOOL_ROLL_LIMIT]),
        np.array([TALOS_TOOL_ROLL_LIMIT]),
    )
    model.appendBodyToJoint(joint, pin.Inertia.FromSphere(0.1, 0.02), pin.SE3.Identity())
    model.addFrame(pin.Frame("tool_roll_link", joint, mount.inverse(), pin.FrameType.OP_FRAME))
    return "tool_roll_link"
