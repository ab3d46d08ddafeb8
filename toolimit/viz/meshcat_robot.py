"""meshcat animation of an optimised robot trajectory: robot, held tool, target and reached poses.

What it draws, as one self-contained HTML page (no meshcat server; built from the pieces of
:mod:`toolimit.viz.meshcat_views`: its server-less visualizer, Pinocchio's meshcat loader, the
per-frame robot placements and the 3D worlds' elements):

* the robot's visual model at its optimised base, one animation frame per trajectory step, played
  at the trajectory's own rate (``1 / dt``, so a slowed-down trajectory plays slowed down). Robots of
  example-robot-data (``panda``, ``ur5``, ``talos``) show that package's meshes, reduced with
  exactly the joints the :class:`~toolimit.robots.RobotModel` locks; a robot without meshes
  (``planar3``) is drawn with primitive capsules along its links and a pedestal under its base;
* the tool's geometry (:mod:`toolimit.scenes.spatial.tool_geometry`) at the robot's tool frame
  (forward kinematics), with a small triad showing the reached tool frame;
* the target tool poses as small triads (every ``target_stride``-th one), the target path and the
  reached path as lines, and a larger triad that follows the current target, so the gap between
  it and the tool's triad is the tracking error of that step;
* optionally a 3D scene (:func:`trajectory_in_scene_html`): the robot's tool motion replayed in
  the scene at its control rate, the scene's elements animated from its ``snapshot()``.

meshcat shows every node at its static placement before the animation starts and once it has
ended, so each animated node is also placed at its first-frame placement.

Frames: world, metres, z up. The arm's universe frame stands at ``(x, y, base_height)`` turned by
``yaw`` about z, as in :mod:`toolimit.robots.model`. A trajectory's ``q`` (T+1, N) has q_0 (the
start) first; step t >= 1 tracks target t (``targets[t - 1]``).
"""

from __future__ import annotations

import functools
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import coal
import meshcat
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
from meshcat.animation import Animation

from toolimit.robots import RobotModel
from toolimit.scenes.base import Scene, SceneParams
from toolimit.scenes.spatial.tool_geometry import tool_shapes
from toolimit.tools import ToolPose, rotation_z
from toolimit.trajopt.execution import resample_joints
from toolimit.trajopt.problem import PoseTargets
from toolimit.trajopt.result import TrajectoryResult
from toolimit.viz.meshcat_views import (
    ROBOT,
    TARGETS,
    TOOL,
    WORLD,
    RobotVisual,
    element_geometry,
    element_material,
    load_geometry,
    replay_scene,
    save_html,
    set_robot_frame,
    static_visualizer,
)
from toolimit.viz.world_elements import GROUND_SIZE, placement, world_elements

#: Robots drawn with example-robot-data's meshes: registry name -> example-robot-data name.
MESH_ROBOTS = {"panda": "panda", "ur5": "ur5", "talos": "talos"}
#: Most target triads drawn by default (a stride is chosen to stay under it).
MAX_TARGET_TRIADS = 24
#: Node paths of the extra drawings.
REACHED_TRIAD = f"{TOOL}/frame"
CURRENT_TARGET = f"{TARGETS}/current"
TARGET_PATH, REACHED_PATH, GROUND = f"{TARGETS}/path", "reached/path", "world/ground"
#: meshcat's camera node and its starting position (three.js axes: y up, z = -world y): in front
#: of the world x-z plane (where ``planar3`` moves), raised and turned a little towards +x.
CAMERA = "/Cameras/default/rotated/<object>"
CAMERA_POSITION = (0.8, 1.0, 2.0)

_TARGET_COLOUR = 0xE6781E
_REACHED_COLOUR = 0x3C8CE6
_LINK_COLOUR = np.array([0.93, 0.93, 0.95, 1.0])
_JOINT_COLOUR = np.array([0.25, 0.27, 0.32, 1.0])
#: Radii of the primitive drawing of a robot without meshes (m).
_LINK_RADIUS, _JOINT_RADIUS = 0.035, 0.05


# ------------------------------------------------------------------------------ visual models
def base_placement(robot: RobotModel, base: np.ndarray) -> np.ndarray:
    """(4, 4) world placement of the arm's universe frame for base (3,) = (x m, y m, yaw rad)."""
    base = np.asarray(base, dtype=float)
    if base.shape != (3,) or not np.all(np.isfinite(base)):
        raise ValueError(f"base must be finite (x, y, yaw) of shape (3,), got {base!r}")
    return placement(np.array([base[0], base[1], robot.base_height]), rotation_z(base[2]))


def visual_geometry(robot: RobotModel) -> pin.GeometryModel:
    """The robot's visual ``GeometryModel``, its objects on the joints of ``robot.model``.

    Meshes of example-robot-data for :data:`MESH_ROBOTS`, primitives otherwise
    (:func:`primitive_geometry`). A new object each call (GeometryModels are mutable).
    """
    if robot.name in MESH_ROBOTS:
        model, geometry = _reduced_mesh_model(robot.name, robot.joint_names)
        _check_same_kinematics(robot, model)
        return geometry.copy()
    return primitive_geometry(robot.model, robot.flange_frame, robot.base_height)


def robot_visual(robot: RobotModel, base: np.ndarray) -> RobotVisual:
    """What :mod:`toolimit.viz.meshcat_views` draws for ``robot`` standing at ``base`` (3,)."""
    return RobotVisual(robot.model, visual_geometry(robot), base_placement(robot, base))


@functools.cache
def _reduced_mesh_model(name: str, keep: tuple[str, ...]) -> tuple[pin.Model, pin.GeometryModel]:
    """example-robot-data's model and visual model with every joint not in ``keep`` locked at q0,
    a free-flyer at the origin (as :mod:`toolimit.robots.arms` builds the kinematic model).
    Cached: loading the URDF and the meshes' paths takes one to three seconds."""
    import example_robot_data

    loaded = example_robot_data.load(MESH_ROBOTS[name])
    q_ref = np.array(loaded.q0, dtype=float)
    if loaded.model.joints[1].shortname() == "JointModelFreeFlyer":
        q_ref[:7] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]
    lock = [j for j in range(1, loaded.model.njoints) if loaded.model.names[j] not in keep]
    model, (geometry,) = pin.buildReducedModel(loaded.model, [loaded.visual_model], lock, q_ref)
    return model, geometry


def _check_same_kinematics(robot: RobotModel, model: pin.Model) -> None:
    """Raise ValueError unless ``model`` has the first joints and joint placements of ``robot.model``
    (the visual geometry hangs on those joints, so they must be the same; the robot may add joints
    after them that no mesh hangs on, as the Talos's tool roll)."""
    if tuple(robot.model.names)[: model.njoints] != tuple(model.names):
        raise ValueError(
            f"{robot.name}: the visual model's joints {tuple(model.names)[1:]} differ from the robot's "
            f"{robot.joint_names}"
        )
    for j in range(1, model.njoints):
        if not model.jointPlacements[j].isApprox(robot.model.jointPlacements[j], 1e-9):
            raise ValueError(f"{robot.name}: joint {model.names[j]} is placed differently in the visual model")


def primitive_geometry(model: pin.Model, flange_frame: str, base_height: float) -> pin.GeometryModel:
    """A visual model of capsules for a robot without meshes.

    A capsule from each joint's origin to each child joint's origin and to the flange, a ball at
    each joint, and a pedestal box (0.12 m square) from the floor (``base_height`` m below the arm's
    universe frame) up to it.
    """
    geometry = pin.GeometryModel()

    def add(name: str, joint: int, where: pin.SE3, shape, colour: np.ndarray) -> None:
        obj = pin.GeometryObject(name, joint, where, shape)
        obj.meshColor = colour
        geometry.addGeometryObject(obj)

    if base_height > 0:
        add(
            "pedestal",
            0,
            pin.SE3(np.eye(3), np.array([0.0, 0.0, -base_height / 2])),
            coal.Box(0.12, 0.12, base_height),
            _JOINT_COLOUR,
        )
    flange = model.frames[model.getFrameId(flange_frame)]
    for joint in range(1, model.njoints):
        add(f"{model.names[joint]}_ball", joint, pin.SE3.Identity(), coal.Sphere(_JOINT_RADIUS), _JOINT_COLOUR)
        children = [c for c in range(joint + 1, model.njoints) if model.parents[c] == joint]
        ends = [model.jointPlacements[c].translation for c in children]
        if flange.parentJoint == joint:
            ends.append(flange.placement.translation)
        for k, end in enumerate(ends):
            length = float(np.linalg.norm(end))
            if length < 1e-6:
                continue
            turn = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), end / length).matrix()
            add(
                f"{model.names[joint]}_link{k}",
                joint,
                pin.SE3(turn, end / 2),
                coal.Capsule(_LINK_RADIUS, length),
                _LINK_COLOUR,
            )
    return geometry


# ------------------------------------------------------------------------------------- inputs
def _target_arrays(targets: PoseTargets | ToolPose, horizon: int) -> tuple[np.ndarray, np.ndarray]:
    """Positions (T, 3) and rotations (T, 3, 3) of PoseTargets or a ToolPose, checked against T."""
    if isinstance(targets, PoseTargets):
        positions, rotations = targets.positions, targets.rotations
    elif isinstance(targets, ToolPose):
        positions = np.asarray(targets.position, dtype=float)
        rotations = np.asarray(targets.rotation, dtype=float)
    else:
        raise TypeError(f"targets must be PoseTargets or a ToolPose, got {type(targets).__name__}")
    if positions.shape != (horizon, 3) or rotations.shape != (horizon, 3, 3):
        raise ValueError(
            f"targets must have one pose per trajectory step: expected ({horizon}, 3) positions and "
            f"({horizon}, 3, 3) rotations, got {positions.shape} and {rotations.shape}"
        )
    return positions, rotations


def _check_trajectory(robot: RobotModel, trajectory: TrajectoryResult) -> np.ndarray:
    """The trajectory's q (T+1, N) after checking it belongs to ``robot``."""
    q = np.asarray(trajectory.q, dtype=float)
    if q.ndim != 2 or q.shape[1] != robot.n_joints or len(q) < 1:
        raise ValueError(f"trajectory q must have shape (T+1, {robot.n_joints}) for {robot.name}, got {q.shape}")
    if tuple(trajectory.joint_names) != tuple(robot.joint_names):
        raise ValueError(
            f"trajectory joints {tuple(trajectory.joint_names)} are not {robot.name}'s {robot.joint_names}"
        )
    if not (np.isfinite(trajectory.dt) and trajectory.dt > 0):
        raise ValueError(f"trajectory dt must be positive, got {trajectory.dt}")
    return q


def default_stride(count: int) -> int:
    """Every how many targets a triad is drawn so that at most :data:`MAX_TARGET_TRIADS` are."""
    return max(1, -(-count // MAX_TARGET_TRIADS))


# ------------------------------------------------------------------------------------ the views
def _line(positions: np.ndarray, colour: int) -> mg.Line:
    """A polyline through positions (K, 3), world frame."""
    return mg.Line(mg.PointsGeometry(np.asarray(positions, dtype=np.float32).T), mg.LineBasicMaterial(color=colour))


def _current_target_index(times: np.ndarray, dt: float, horizon: int) -> np.ndarray:
    """Index (0-based) of the target tracked at each animation time (s): step t >= 1 at time t dt
    tracks target t; the start (time 0) shows the first target."""
    return np.clip(np.rint(times / dt).astype(int), 1, horizon) - 1


def _animated_view(
    robot: RobotModel,
    q_frames: np.ndarray,
    base: np.ndarray,
    frame_dt: float,
    *,
    dt: float | None = None,
    targets: tuple[np.ndarray, np.ndarray] | None = None,
    target_stride: int | None = None,
    triad_scale: float = 0.1,
    world_frames: Sequence[Mapping[str, np.ndarray]] | None = None,
) -> meshcat.Visualizer:
    """The animated robot view of the trajectory and rollout pages.

    ``q_frames`` (F, N) joint positions (rad) of the F animation frames, ``frame_dt`` (s) apart;
    ``dt`` (s, ``frame_dt`` when None) is the trajectory's own step, which maps frames to targets; ``targets`` the T target
    positions (T, 3) and rotations (T, 3, 3); ``world_frames`` F scene snapshots, or None for a
    plain ground. Every animated node is also placed at its first-frame placement, which meshcat
    shows before the animation starts and once it has finished.
    """
    visual = robot_visual(robot, base)
    positions, rotations = robot.tool_poses(q_frames, base)
    visualizer = static_visualizer(title=f"toolimit {robot.name} trajectory")
    visualizer[CAMERA].set_property("position", list(CAMERA_POSITION))

    if world_frames is None:
        centre = np.vstack([visual.base_placement[:3, 3], positions]).mean(axis=0)
        visualizer[GROUND].set_object(mg.Box([GROUND_SIZE, GROUND_SIZE, 0.01]), mg.MeshLambertMaterial(color=0xD9D9CC))
        visualizer[GROUND].set_transform(placement(np.array([centre[0], centre[1], -0.005])))
    else:
        for element in world_elements(robot.tool.name, world_frames[0]):
            visualizer[f"{WORLD}/{element.path}"].set_object(
                element_geometry(element), element_material(element.colour)
            )
            visualizer[f"{WORLD}/{element.path}"].set_transform(element.transform)

    robot_viz = load_geometry(visualizer, visual.model, visual.visual_model, ROBOT)
    visualizer[ROBOT].set_transform(visual.base_placement)
    set_robot_frame(visualizer, robot_viz, q_frames[0])
    tool_viz = load_geometry(visualizer, pin.Model(), tool_shapes(robot.tool.name).geometry_model, TOOL)
    tool_viz.display(np.zeros(0))  # shapes at their tool-frame placements under the "tool" node
    visualizer[TOOL].set_transform(placement(positions[0], rotations[0]))
    visualizer[REACHED_TRIAD].set_object(mg.triad(triad_scale))
    if len(positions) > 1:
        visualizer[REACHED_PATH].set_object(_line(positions, _REACHED_COLOUR))

    current = None
    if targets is not None:
        target_positions, target_rotations = targets
        stride = default_stride(len(target_positions)) if target_stride is None else target_stride
        if stride < 1:
            raise ValueError(f"target_stride must be >= 1, got {stride}")
        for k in range(0, len(target_positions), stride):
            visualizer[f"{TARGETS}/{k}"].set_object(mg.triad(0.6 * triad_scale))
            visualizer[f"{TARGETS}/{k}"].set_transform(placement(target_positions[k], target_rotations[k]))
        if len(target_positions) > 1:
            visualizer[TARGET_PATH].set_object(_line(target_positions, _TARGET_COLOUR))
        step = frame_dt if dt is None else dt
        indices = _current_target_index(np.arange(len(q_frames)) * frame_dt, step, len(target_positions))
        current = [placement(target_positions[i], target_rotations[i]) for i in indices]
        visualizer[CURRENT_TARGET].set_object(mg.triad(1.5 * triad_scale))
        visualizer[CURRENT_TARGET].set_transform(current[0])

    animation = Animation(default_framerate=1.0 / frame_dt)
    for index, q in enumerate(q_frames):
        with animation.at_frame(visualizer, index) as frame:
            frame[TOOL].set_transform(placement(positions[index], rotations[index]))
            set_robot_frame(frame, robot_viz, q)
            if current is not None:
                frame[CURRENT_TARGET].set_transform(current[index])
            if world_frames is not None and index > 0:
                for element in world_elements(robot.tool.name, world_frames[index]):
                    frame[f"{WORLD}/{element.path}"].set_transform(element.transform)
    visualizer.set_animation(animation, play=True, repetitions=1)
    return visualizer


def trajectory_visualizer(
    robot: RobotModel,
    trajectory: TrajectoryResult,
    targets: PoseTargets | ToolPose | None = None,
    target_stride: int | None = None,
    triad_scale: float = 0.1,
) -> meshcat.Visualizer:
    """A server-less visualizer holding the animated robot trajectory (see the module docstring).

    Args:
        robot: the robot (``make_robot(trajectory.robot, tool=trajectory.tool)``).
        trajectory: q (T+1, N) rad, base (3,), dt s (a :class:`TrajectoryResult` or alike).
        targets: the T target tool poses (world frame) the trajectory tracks, or None.
        target_stride: draw a triad at every ``target_stride``-th target (default: at most
            :data:`MAX_TARGET_TRIADS` triads); the current target's triad is always animated.
        triad_scale: axis length of the tool-frame and current-target triads, m.
    """
    q = _check_trajectory(robot, trajectory)
    arrays = None if targets is None else _target_arrays(targets, len(q) - 1)
    return _animated_view(
        robot, q, trajectory.base, trajectory.dt, targets=arrays, target_stride=target_stride, triad_scale=triad_scale
    )


def trajectory_to_html(
    path: str | os.PathLike[str],
    robot: RobotModel,
    trajectory: TrajectoryResult,
    targets: PoseTargets | ToolPose | None = None,
    target_stride: int | None = None,
) -> Path:
    """Write :func:`trajectory_visualizer`'s animation as one self-contained HTML file (atomically)."""
    return save_html(trajectory_visualizer(robot, trajectory, targets, target_stride), path)


def trajectory_in_scene_html(
    path: str | os.PathLike[str],
    robot: RobotModel,
    trajectory: TrajectoryResult,
    scene: Scene,
    params: SceneParams,
    rng: np.random.Generator,
    targets: PoseTargets | ToolPose | None = None,
    target_stride: int | None = None,
    triad_scale: float = 0.1,
) -> Path:
    """The robot's trajectory replayed in a 3D ``scene``, written as one self-contained HTML file.

    As :func:`toolimit.trajopt.execute_in_scene` does, the joints are resampled at the scene's
    control rate and the tool follows forward kinematics at ``trajectory.base``; the scene is reset
    with ``params`` and ``rng`` and its state drawn at every control step, with everything
    :func:`trajectory_visualizer` draws (the ground is the scene's).
    """
    q = _check_trajectory(robot, trajectory)
    if scene.tool != robot.tool.name:
        raise ValueError(f"the scene is a {scene.tool} scene but {robot.name} holds a {robot.tool.name}")
    arrays = None if targets is None else _target_arrays(targets, len(q) - 1)
    q_control = resample_joints(q, trajectory.dt, scene.control_dt)
    positions, rotations = robot.tool_poses(q_control, trajectory.base)
    frames = replay_scene(scene, ToolPose(positions, rotations), params, rng, tool_alone=False)
    visualizer = _animated_view(
        robot,
        q_control,
        trajectory.base,
        scene.control_dt,
        dt=trajectory.dt,
        targets=arrays,
        target_stride=target_stride,
        triad_scale=triad_scale,
        world_frames=frames,
    )
    return save_html(visualizer, path)
