"""meshcat animation of a robot trajectory (robot + tool + targets) as self-contained HTML, no server."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from toolimit.robots import make_robot
from toolimit.scenes.spatial.hammer import SpatialHammerScene
from toolimit.scenes.spatial.spade import SpatialSpadeScene
from toolimit.trajopt import PoseTargets, TrajectoryResult
from toolimit.trajopt.track import evaluate_trajectory
from toolimit.viz.meshcat_robot import (
    CURRENT_TARGET,
    REACHED_TRIAD,
    TARGET_PATH,
    base_placement,
    trajectory_in_scene_html,
    trajectory_to_html,
    visual_geometry,
)

STEPS = 5
DT = 2.0 / 24.0  # a trajectory slowed down twice: the animation must play at 12 fps
BASES = {"panda": np.array([0.3, -0.2, 0.4]), "planar3": np.array([0.3, 0.0, 0.0])}


def make_trajectory(robot_name: str) -> tuple:
    """A robot, a short joint trajectory (first joint turning) and targets 2 cm off what it reaches."""
    robot = make_robot(robot_name, tool="spade")
    q = np.tile(robot.q_neutral, (STEPS + 1, 1))
    q[:, 0] += np.linspace(0.0, 0.6, STEPS + 1)
    base = BASES[robot_name]
    positions, rotations = robot.tool_poses(q[1:], base)
    targets = PoseTargets(positions + [0.0, 0.0, 0.02], rotations, fps=24.0)
    trajectory = evaluate_trajectory(robot, targets, base, q, DT, 2.0, None)
    return robot, trajectory, targets


def clips_of(commands: list[dict]) -> dict[str, dict]:
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    return {entry["path"]: entry["clip"] for entry in animation["animations"]}


def transforms_of(clip: dict) -> list[np.ndarray]:
    """(4, 4) transforms of every key of a clip (three.js quaternion order x, y, z, w)."""
    tracks = {track["name"]: track["keys"] for track in clip["tracks"]}
    result = []
    for position, quaternion in zip(tracks[".position"], tracks[".quaternion"]):
        x, y, z, w = quaternion["value"]
        result.append(pin.SE3(pin.Quaternion(w, x, y, z).matrix(), np.array(position["value"])).homogeneous)
    return result


def static_transform(commands: list[dict], path: str) -> np.ndarray:
    command = next(c for c in commands if c["type"] == "set_transform" and c["path"] == path)
    return np.reshape(command["matrix"], (4, 4)).T


@pytest.mark.parametrize("robot_name", ["panda", "planar3"])
def test_trajectory_html_animates_robot_tool_and_targets(tmp_path, html_commands, robot_name):
    robot, trajectory, targets = make_trajectory(robot_name)
    path = trajectory_to_html(tmp_path / f"{robot_name}.html", robot, trajectory, targets, target_stride=2)
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and "MeshCat.Viewer" in text
    assert not list(tmp_path.glob(".*")), "a temporary file was left behind"
    commands = html_commands(path)
    objects = {c["path"] for c in commands if c["type"] == "set_object"}

    robot_shapes = {p for p in objects if p.startswith("/meshcat/robot/visuals/")}
    assert len(robot_shapes) == len(visual_geometry(robot).geometryObjects) >= 7
    assert {"/meshcat/tool/visuals/spade/blade", "/meshcat/tool/visuals/spade/handle"} <= objects
    assert {f"/meshcat/{REACHED_TRIAD}", f"/meshcat/{CURRENT_TARGET}", f"/meshcat/{TARGET_PATH}"} <= objects
    assert {p for p in objects if p.split("/")[-1].isdigit()} == {f"/meshcat/targets/{k}" for k in (0, 2, 4)}
    np.testing.assert_allclose(static_transform(commands, "/meshcat/robot"), base_placement(robot, trajectory.base),
                               atol=1e-6)

    clips = clips_of(commands)
    assert clips["/meshcat/tool"]["fps"] == pytest.approx(1.0 / DT)
    tool = transforms_of(clips["/meshcat/tool"])
    assert len(tool) == STEPS + 1
    for frame, q in zip(tool, trajectory.q):  # the tool is drawn where forward kinematics puts it
        position, rotation = robot.tool_pose(q, trajectory.base)
        np.testing.assert_allclose(frame[:3, 3], position, atol=1e-5)
        np.testing.assert_allclose(frame[:3, :3], rotation, atol=1e-5)
    current = transforms_of(clips[f"/meshcat/{CURRENT_TARGET}"])
    np.testing.assert_allclose([c[:3, 3] for c in current[1:]], targets.positions, atol=1e-5)

    # the tool is rigidly held by the last link: their relative placement never changes, though the arm moves
    base = base_placement(robot, trajectory.base)
    last_link = [p for p in clips if p.startswith("/meshcat/robot/visuals/")][-1]
    link = [base @ m for m in transforms_of(clips[last_link])]
    grip = [np.linalg.inv(at_link) @ at_tool for at_link, at_tool in zip(link, tool)]
    for g in grip[1:]:
        np.testing.assert_allclose(g, grip[0], atol=1e-5)
    assert np.linalg.norm(link[-1][:3, 3] - link[0][:3, 3]) > 0.05
    # before and after the animation meshcat shows the static placements: those of the first frame
    np.testing.assert_allclose(base @ static_transform(commands, last_link), link[0], atol=1e-5)
    np.testing.assert_allclose(static_transform(commands, "/meshcat/tool"), tool[0], atol=1e-5)


def test_mesh_visual_model_locks_the_same_joints_as_the_robot():
    talos = make_robot("talos", tool="spade")
    geometry = visual_geometry(talos)
    # every arm joint carries meshes; the authors' tool roll (added after the gripper) none
    assert max(obj.parentJoint for obj in geometry.geometryObjects) == talos.model.getJointId("arm_right_7_joint")
    assert talos.model.names[-1] == "tool_roll_joint"
    names = {obj.name.rsplit("_", 1)[0] for obj in geometry.geometryObjects}
    assert any(name.startswith("leg_left") for name in names)  # locked parts are still drawn


def test_trajectory_replayed_in_a_scene(tmp_path, html_commands):
    robot, trajectory, targets = make_trajectory("panda")
    head, _ = robot.tool_pose(trajectory.q[0], trajectory.base)
    params = {"sand_position": np.array([head[0], head[1], 0.0]), "sand_yaw": 0.0,
              "goal_position": np.array([head[0] + 0.5, head[1], 0.0])}
    path = trajectory_in_scene_html(tmp_path / "scene.html", robot, trajectory, SpatialSpadeScene(n_spheres=30),
                                    params, np.random.default_rng(0), targets)
    commands = html_commands(path)
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    assert sum(p.startswith("/meshcat/world/sand/") for p in objects) == 30
    assert any(p.startswith("/meshcat/robot/visuals/panda_link") for p in objects)
    assert f"/meshcat/{CURRENT_TARGET}" in objects
    clips = clips_of(commands)
    # resampled from dt = 1/12 s to the scene's 1/24 s: twice as many frames (minus one)
    tool = transforms_of(clips["/meshcat/tool"])
    assert len(tool) == 2 * STEPS + 1
    assert clips["/meshcat/tool"]["fps"] == pytest.approx(24.0)
    np.testing.assert_allclose(tool[-1][:3, 3], robot.tool_pose(trajectory.q[-1], trajectory.base)[0], atol=1e-5)
    np.testing.assert_allclose(tool[1][:3, 3], robot.tool_pose(trajectory.q[:2].mean(axis=0), trajectory.base)[0],
                               atol=1e-5)  # halfway between the first two steps, in joint space
    # the current target advances every second frame (the trajectory's own rate)
    current = [c[:3, 3] for c in transforms_of(clips[f"/meshcat/{CURRENT_TARGET}"])]
    np.testing.assert_allclose(current[2::2], targets.positions, atol=1e-5)
    sand = [p for p in clips if p.startswith("/meshcat/world/sand/")]
    assert len(sand) == 30 and len(transforms_of(clips[sand[0]])) == 2 * STEPS  # frames 1.. (0 is static)


def test_bad_inputs_write_nothing(tmp_path):
    robot, trajectory, targets = make_trajectory("planar3")
    target = tmp_path / "bad.html"
    short = PoseTargets(targets.positions[:-1], targets.rotations[:-1], targets.fps)
    with pytest.raises(ValueError, match=r"one pose per trajectory step: expected \(5, 3\)"):
        trajectory_to_html(target, robot, trajectory, short)
    panda = make_robot("panda", tool="spade")
    with pytest.raises(ValueError, match=r"shape \(T\+1, 7\) for panda"):
        trajectory_to_html(target, panda, trajectory)
    renamed = TrajectoryResult(**{**trajectory.__dict__, "joint_names": ("a", "b", "c")})
    with pytest.raises(ValueError, match="are not planar3's"):
        trajectory_to_html(target, robot, renamed)
    with pytest.raises(ValueError, match="hammer scene"):
        trajectory_in_scene_html(target, robot, trajectory, SpatialHammerScene(), {}, np.random.default_rng(0))
    assert not list(tmp_path.iterdir())
