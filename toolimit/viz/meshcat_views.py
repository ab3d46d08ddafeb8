"""meshcat views of the 3D worlds: a scene replay (+ robot + target poses) as one self-contained HTML.

Why no server: ``meshcat.Visualizer()`` (meshcat 0.3.2) always starts a ``meshcat.servers.zmqserver``
subprocess and only asks it for the scene when ``static_html()`` is called; ``Visualizer.close()``
fails (its window has no ``close``), so the process lingers until the interpreter exits. Here a
:class:`StaticViewerWindow` takes the server's place in-process: it keeps meshcat's own scene tree
(``meshcat.servers.tree``) exactly as the server does and writes the same static page (meshcat's
``main.min.js`` + the recorded commands, via the server's ``create_command``). Everything else is
plain meshcat and Pinocchio: ``meshcat.Visualizer(window=...)``, ``meshcat.geometry``,
``meshcat.animation.Animation`` (24 fps), and ``pinocchio.visualize.MeshcatVisualizer`` to turn
the tool's and the robot's ``GeometryModel`` (coal shapes, meshes) into meshcat objects.

World frame: metres, z up, ground z = 0. Frames of a replay are scene ``snapshot()`` dicts (instance
0), one per control step; :mod:`toolimit.viz.world_elements` reads the snapshot keys of each world.
"""

from __future__ import annotations

import base64
import gzip
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import meshcat
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
import umsgpack
from meshcat.animation import Animation
from meshcat.servers.tree import SceneTree, find_node, walk
from meshcat.servers.zmqserver import VIEWER_ROOT
from pinocchio.visualize import MeshcatVisualizer
from pinocchio.visualize.meshcat_visualizer import applyScalingOnHomegeneousTransform

from toolimit.artifacts import atomic_path
from toolimit.scenes.base import CONTROL_FPS, Scene, SceneParams
from toolimit.scenes.replay import replay
from toolimit.scenes.spatial.tool_geometry import tool_shapes
from toolimit.tools import ToolPose
from toolimit.viz.world_elements import Element, placement, world_elements

#: Root paths of the drawn parts in the meshcat tree.
WORLD, TOOL, ROBOT, TARGETS = "world", "tool", "robot", "targets"

_HTML = """<!DOCTYPE html>
<html>
    <head> <meta charset=utf-8> <title>{title}</title> </head>
    <body>
        <div id="meshcat-pane"></div>
        <script>
{mainminjs}
        </script>
        <script>
            var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
            // each command: gzip-compressed msgpack, run in the order recorded
            async function run(commands) {{
                for (const command of commands) {{
                    const packed = await fetch("data:application/gzip;base64," + command);
                    const stream = packed.body.pipeThrough(new DecompressionStream("gzip"));
                    viewer.handle_command_bytearray(new Uint8Array(await new Response(stream).arrayBuffer()));
                }}
            }}
            run([
{commands}
            ]);
        </script>
        <style>
            body {{margin: 0; }}
            #meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
        </style>
    </body>
</html>
"""


class StaticViewerWindow:
    """In-process stand-in for meshcat's ``ViewerWindow``: records commands, writes static HTML.

    It stores each command in meshcat's scene tree as the zmq server does (objects, properties,
    transforms, animation per node; ``delete`` removes a subtree), so :meth:`get_scene` returns the
    page the server would, without a process, a socket or a port.
    """

    def __init__(self, title: str = "toolimit") -> None:
        self.title = title
        self.tree = SceneTree()

    def send(self, command) -> None:
        """Record one meshcat command (anything with ``lower()`` giving a dict with a ``path``)."""
        data = command.lower()
        kind = data["type"]
        path = [part for part in data["path"].split("/") if part]
        packed = umsgpack.packb(data)
        if kind == "delete":
            if path:
                find_node(self.tree, path[:-1]).pop(path[-1], None)
            else:
                self.tree = SceneTree()
            return
        node = find_node(self.tree, path)
        if kind == "set_object":
            node.object, node.properties = packed, []
        elif kind == "set_transform":
            node.transform = packed
        elif kind == "set_property":
            node.properties.append(packed)
        elif kind == "set_animation":
            node.animation = packed
        else:
            raise ValueError(f"unsupported meshcat command {kind!r} in a static view")

    def get_scene(self) -> str:
        """The self-contained HTML page: meshcat's viewer script and the recorded scene, each
        command gzip-compressed (the browser's ``DecompressionStream`` inflates it): a Panda rollout
        page (the shipped 3D spade task, every other frame) takes 6.5 MB instead of meshcat's 19.2 MB,
        nearly all of it the robot's meshes."""
        packed: list[bytes] = []
        for node in walk(self.tree):
            if node.object is not None:
                packed.append(node.object)
            packed.extend(node.properties)
            if node.transform is not None:
                packed.append(node.transform)
            if node.animation is not None:
                packed.append(node.animation)
        commands = ",\n".join(
            f'"{base64.b64encode(gzip.compress(data, compresslevel=6, mtime=0)).decode()}"' for data in packed
        )
        script = (Path(VIEWER_ROOT) / "main.min.js").read_text(encoding="utf-8")
        return _HTML.format(title=self.title, mainminjs=script, commands=commands)

    def close(self) -> None:
        """Nothing to release (no server); present so ``Visualizer.close()`` works."""


def static_visualizer(title: str = "toolimit") -> meshcat.Visualizer:
    """A ``meshcat.Visualizer`` that starts no server; ``static_html()`` gives the page."""
    return meshcat.Visualizer(window=StaticViewerWindow(title))


def save_html(visualizer: meshcat.Visualizer, path: str | os.PathLike[str]) -> Path:
    """Write ``visualizer.static_html()`` to ``path`` atomically (temp file + rename)."""
    target = Path(path)
    html = visualizer.static_html()
    with atomic_path(target) as tmp:
        tmp.write_text(html, encoding="utf-8")
    return target


# ------------------------------------------------------------------------------ world elements
def element_geometry(element: Element) -> mg.Geometry:
    """meshcat geometry of a world element."""
    if element.shape == "sphere":
        return mg.Sphere(float(element.size[0]))
    return mg.Box(tuple(2.0 * element.size))


def element_material(colour: Sequence[float]) -> mg.MeshLambertMaterial:
    red, green, blue, alpha = (float(c) for c in colour)
    rgb = (int(red * 255) << 16) + (int(green * 255) << 8) + int(blue * 255)
    return mg.MeshLambertMaterial(color=rgb, opacity=alpha, transparent=alpha < 1.0)


# ------------------------------------------------------------------------------- tool and robot
@dataclass(frozen=True)
class RobotVisual:
    """A robot to draw: Pinocchio model, its visual geometry, and where its base stands.

    Attributes:
        model: ``pin.Model`` whose configurations are given per frame.
        visual_model: ``pin.GeometryModel`` of the model's visual shapes (meshes or coal shapes).
        base_placement: (4, 4) world placement of the model's universe frame.
    """

    model: pin.Model
    visual_model: pin.GeometryModel
    base_placement: np.ndarray = field(default_factory=lambda: np.eye(4))


def load_geometry(
    visualizer: meshcat.Visualizer, model: pin.Model, geometry: pin.GeometryModel, root: str
) -> MeshcatVisualizer:
    """Load a GeometryModel's shapes under ``root`` with Pinocchio's meshcat loader."""
    viz = MeshcatVisualizer(model, None, geometry)
    viz.initViewer(viewer=visualizer)
    viz.loadViewerModel(rootNodeName=root)
    return viz


def _pose_matrix(position: np.ndarray, rotation: np.ndarray) -> np.ndarray | None:
    """(4, 4) tool placement, or None when the pose is not set (NaN before the first step)."""
    if not (np.all(np.isfinite(position)) and np.all(np.isfinite(rotation))):
        return None
    return placement(position, rotation)


def _targets_matrices(targets: ToolPose | np.ndarray) -> np.ndarray:
    """(K, 4, 4) target placements from a ToolPose (K, 3)/(K, 3, 3) or matrices (K, 4, 4)."""
    if isinstance(targets, ToolPose):
        position = np.asarray(targets.position, dtype=float).reshape(-1, 3)
        rotation = np.asarray(targets.rotation, dtype=float).reshape(-1, 3, 3)
        return np.array([placement(p, r) for p, r in zip(position, rotation)])
    matrices = np.asarray(targets, dtype=float)
    if matrices.ndim != 3 or matrices.shape[1:] != (4, 4):
        raise ValueError(f"targets must be a ToolPose or (K, 4, 4) matrices, got shape {matrices.shape}")
    return matrices


def replay_to_html(
    path: str | os.PathLike[str],
    frames: Sequence[Mapping[str, np.ndarray]],
    tool: str,
    robot: RobotVisual | None = None,
    robot_q: np.ndarray | None = None,
    targets: ToolPose | np.ndarray | None = None,
    fps: float = CONTROL_FPS,
    target_scale: float = 0.08,
) -> Path:
    """Write the animated replay as one self-contained HTML file (a server-less meshcat visualizer).

    Args:
        path: the .html file to write.
        frames: scene snapshots (instance 0), one per animation frame; each has ``tool_position``
            (3,) and ``tool_rotation`` (3, 3) (NaN while the tool is absent) plus the world's keys.
        tool: "spade", "hammer" or "scythe": chooses the world drawing and the tool geometry.
        robot: optional robot to draw; ``robot_q`` (len(frames), nq) its configurations.
        targets: optional target tool poses drawn as triads (ToolPose (K, 3)/(K, 3, 3) or (K, 4, 4)).
        fps: animation frame rate (the scenes' control rate by default).
        target_scale: triad axis length, m.
    """
    if len(frames) == 0:
        raise ValueError("a replay needs at least one frame")
    if (robot is None) != (robot_q is None):
        raise ValueError("robot and robot_q must be given together")
    visualizer = static_visualizer(title=f"toolimit {tool} replay")
    first = world_elements(tool, frames[0])
    for element in first:
        visualizer[f"{WORLD}/{element.path}"].set_object(element_geometry(element), element_material(element.colour))
        visualizer[f"{WORLD}/{element.path}"].set_transform(element.transform)
    tool_viz = load_geometry(visualizer, pin.Model(), tool_shapes(tool).geometry_model, TOOL)
    tool_viz.display(np.zeros(0))  # shapes at their tool-frame placements under the "tool" node

    robot_viz = None
    robot_frames = np.zeros((len(frames), 0))  # (F, nq) joint positions of the robot, rad
    if robot is not None:
        robot_frames = np.asarray(robot_q, dtype=float)
        if robot_frames.shape != (len(frames), robot.model.nq):
            raise ValueError(f"robot_q must have shape ({len(frames)}, {robot.model.nq}), got {robot_frames.shape}")
        robot_viz = load_geometry(visualizer, robot.model, robot.visual_model, ROBOT)
        visualizer[ROBOT].set_transform(np.asarray(robot.base_placement, dtype=float))
    if targets is not None:
        for k, matrix in enumerate(_targets_matrices(targets)):
            visualizer[f"{TARGETS}/{k}"].set_object(mg.triad(target_scale))
            visualizer[f"{TARGETS}/{k}"].set_transform(matrix)

    tool_poses = [_pose_matrix(f["tool_position"], f["tool_rotation"]) for f in frames]
    placed = [pose for pose in tool_poses if pose is not None]
    # meshcat returns every node to its static placement once the animation has played, so give
    # the tool and the robot their first-frame poses as static placements too.
    if placed:
        visualizer[TOOL].set_transform(placed[0])
    if robot_viz is not None:
        set_robot_frame(visualizer, robot_viz, robot_frames[0])
    animation = Animation(default_framerate=fps)
    for index, snapshot in enumerate(frames):
        with animation.at_frame(visualizer, index) as frame:
            elements = first if index == 0 else world_elements(tool, snapshot)
            for element in elements:
                frame[f"{WORLD}/{element.path}"].set_transform(element.transform)
            pose = tool_poses[index] if tool_poses[index] is not None else (placed[0] if placed else None)
            if pose is not None:
                frame[TOOL].set_transform(pose)
            if robot_viz is not None:
                set_robot_frame(frame, robot_viz, robot_frames[index])
    if not placed:
        visualizer[TOOL].set_property("visible", False)
    visualizer.set_animation(animation, play=True, repetitions=1)
    return save_html(visualizer, path)


def set_robot_frame(frame, robot_viz: MeshcatVisualizer, q: np.ndarray) -> None:
    """Place the robot's visual nodes at configuration q (nq,), in an animation frame or a visualizer."""
    pin.forwardKinematics(robot_viz.model, robot_viz.data, q)
    pin.updateGeometryPlacements(robot_viz.model, robot_viz.data, robot_viz.visual_model, robot_viz.visual_data)
    for index, geometry in enumerate(robot_viz.visual_model.geometryObjects):
        transform = applyScalingOnHomegeneousTransform(robot_viz.visual_data.oMg[index].homogeneous, geometry.meshScale)
        frame[robot_viz.getViewerNodeName(geometry, pin.GeometryType.VISUAL)].set_transform(transform)


# -------------------------------------------------------------------------------------- replays
def replay_scene(
    scene: Scene, poses: ToolPose, params: SceneParams, rng: np.random.Generator, tool_alone: bool = True
) -> list[dict[str, np.ndarray]]:
    """Reset one instance of ``scene`` with ``params``, step it through ``poses`` (T, 3)/(T, 3, 3)
    and return the T snapshots taken after each step (the frames of a replay); ``tool_alone`` as
    :func:`toolimit.scenes.replay.replay` (False for a robot's forward kinematics)."""
    position = np.asarray(poses.position, dtype=float)
    rotation = np.asarray(poses.rotation, dtype=float)
    if position.ndim != 2 or position.shape[1] != 3 or rotation.shape != (len(position), 3, 3):
        raise ValueError(
            f"poses must be (T, 3) positions and (T, 3, 3) rotations, got {position.shape} and {rotation.shape}"
        )
    frames: list[dict[str, np.ndarray]] = []
    replay(
        scene,
        params,
        rng,
        ToolPose(position, rotation),
        on_step=lambda _, stepped: frames.append(stepped.snapshot()),
        tool_alone=tool_alone,
    )
    return frames


def scene_replay_html(
    path: str | os.PathLike[str],
    scene: Scene,
    poses: ToolPose,
    params: SceneParams,
    rng: np.random.Generator,
    robot: RobotVisual | None = None,
    robot_q: np.ndarray | None = None,
    show_targets: bool = False,
) -> Path:
    """Replay ``poses`` in ``scene`` and write the animation as a self-contained HTML file.

    ``show_targets`` draws every pose as a small triad (the path the tool should follow).
    """
    frames = replay_scene(scene, poses, params, rng)
    targets = poses if show_targets else None
    return replay_to_html(path, frames, scene.tool, robot, robot_q, targets, fps=1.0 / scene.control_dt)
