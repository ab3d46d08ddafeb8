"""meshcat replays of the 3D worlds as self-contained HTML, without any meshcat server."""

from __future__ import annotations

import example_robot_data
import meshcat
import numpy as np
import pytest

from toolimit.scenes.spatial.hammer import SpatialHammerScene
from toolimit.scenes.spatial.scythe import SpatialScytheScene
from toolimit.scenes.spatial.spade import SpatialSpadeScene
from toolimit.scenes.spatial.sweep import pull
from toolimit.tools import ToolPose, rotation_z, tool_poses
from toolimit.viz.meshcat_views import (
    RobotVisual,
    StaticViewerWindow,
    replay_scene,
    replay_to_html,
    save_html,
    scene_replay_html,
    static_visualizer,
)

N_FRAMES = 6
FACE_DOWN = np.column_stack([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def animation_clips(commands: list[dict]) -> dict[str, dict]:
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    return {entry["path"]: entry["clip"] for entry in animation["animations"]}


def key_count(clip: dict) -> int:
    return len(clip["tracks"][0]["keys"])


def hammer_poses() -> ToolPose:
    z = 0.3 + 0.055 + np.linspace(0.15, -0.01, N_FRAMES)
    position = np.column_stack([np.full(N_FRAMES, 0.5), np.full(N_FRAMES, 0.2), z])
    return ToolPose(position, np.broadcast_to(FACE_DOWN, (N_FRAMES, 3, 3)).copy())


def test_hammer_replay_html_holds_the_scene_and_its_animation(tmp_path, html_commands):
    path = scene_replay_html(
        tmp_path / "hammer.html",
        SpatialHammerScene(),
        hammer_poses(),
        {"nail_position": np.array([0.5, 0.2, 0.3])},
        np.random.default_rng(0),
        show_targets=True,
    )
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and "MeshCat.Viewer" in text
    commands = html_commands(path)
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    assert {"/meshcat/world/board", "/meshcat/world/nail/plate", "/meshcat/tool/visuals/hammer/head"} <= objects
    assert sum(p.startswith("/meshcat/targets/") for p in objects) == N_FRAMES
    clips = animation_clips(commands)
    assert key_count(clips["/meshcat/tool"]) == N_FRAMES
    assert clips["/meshcat/tool"]["fps"] == pytest.approx(24.0)
    plate_z = [k["value"][2] for k in clips["/meshcat/world/nail/plate"]["tracks"][0]["keys"]]
    assert plate_z[-1] < plate_z[0]  # the strike drove the nail: the animation shows it
    assert not list(tmp_path.glob(".*"))  # no temporary file left behind


def test_scythe_replay_shows_cut_stalks_fallen(tmp_path, html_commands):
    # the level scythe pulled towards its handle (-y) across the patch at 1.5 m/s, then still; replayed
    # as given (as a robot's forward kinematics): the tool alone's 1 m/s limit is below the rule's approach
    pulled = pull(np.array([1.0, 0.0, 0.05]), 0.15, -0.15, 1.5, 1.0 / 24)
    index = np.minimum(np.arange(N_FRAMES), len(pulled.position) - 1)
    frames_poses = ToolPose(pulled.position[index], pulled.rotation[index])
    scene = SpatialScytheScene(n_stalks=20, patch_size=(0.3, 0.1))
    params = {"grass_position": np.array([1.0, 0.0, 0.0])}
    frames = replay_scene(scene, frames_poses, params, np.random.default_rng(1), tool_alone=False)
    assert frames[-1]["stalk_cut"].all() and not frames[0]["stalk_cut"].any()
    path = replay_to_html(tmp_path / "scythe.html", frames, "scythe")
    clips = animation_clips(html_commands(path))
    stalk = clips["/meshcat/world/stalks/0"]
    positions = next(t for t in stalk["tracks"] if t["name"] == ".position")["keys"]
    assert positions[0]["value"][2] == pytest.approx(0.15)  # standing: centre at half height
    assert positions[-1]["value"][2] == pytest.approx(0.0025)  # fallen: lying on the ground


def test_spade_replay_with_a_robot_and_targets(tmp_path, html_commands):
    panda = example_robot_data.load("panda")
    scene = SpatialSpadeScene(n_spheres=30)
    params = {
        "sand_position": np.array([0.6, 0.0, 0.0]),
        "sand_yaw": 0.0,
        "goal_position": np.array([0.6, 0.6, 0.0]),
    }
    head = np.column_stack([np.full(N_FRAMES, 0.6), np.linspace(-0.1, 0.3, N_FRAMES), np.full(N_FRAMES, 0.05)])
    poses = tool_poses(head, head + [0.0, -0.2, 0.3])
    frames = replay_scene(scene, poses, params, np.random.default_rng(0))
    q = np.tile(panda.q0, (N_FRAMES, 1))
    q[:, 0] = np.linspace(0.0, 1.0, N_FRAMES)
    base = np.eye(4)
    base[:3, :3] = rotation_z(0.3)
    robot = RobotVisual(panda.model, panda.visual_model, base)
    path = replay_to_html(tmp_path / "spade.html", frames, "spade", robot=robot, robot_q=q, targets=poses)
    commands = html_commands(path)
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    assert sum(p.startswith("/meshcat/world/sand/") for p in objects) == 30
    assert any(p.startswith("/meshcat/world/walls/") for p in objects)
    robot_transform = next(c for c in commands if c["type"] == "set_transform" and c["path"] == "/meshcat/robot")
    np.testing.assert_allclose(np.reshape(robot_transform["matrix"], (4, 4)).T, base, atol=1e-6)
    clips = animation_clips(commands)
    link1 = next(p for p in clips if p.startswith("/meshcat/robot/visuals/panda_link1"))
    quaternions = next(t for t in clips[link1]["tracks"] if t["name"] == ".quaternion")["keys"]
    assert len(quaternions) == N_FRAMES
    assert not np.allclose(quaternions[0]["value"], quaternions[-1]["value"])  # joint 1 turns


def test_bad_frames_write_nothing(tmp_path):
    target = tmp_path / "bad.html"
    with pytest.raises(ValueError, match="lacks the key"):
        replay_to_html(target, [{"tool_position": np.zeros(3), "tool_rotation": np.eye(3)}], "hammer")
    with pytest.raises(ValueError, match="robot_q"):
        replay_to_html(target, [{}], "hammer", robot_q=np.zeros((1, 7)))
    assert not list(tmp_path.iterdir())


def test_static_window_mirrors_the_server_tree(tmp_path, html_commands):
    visualizer = static_visualizer()
    visualizer["a/b"].set_object(meshcat.geometry.Box([0.1, 0.1, 0.1]))
    visualizer["a/c"].set_object(meshcat.geometry.Sphere(0.2))
    visualizer["a/c"].set_transform(np.eye(4))
    visualizer["a/b"].delete()
    window = visualizer.window
    assert isinstance(window, StaticViewerWindow)
    assert "b" not in window.tree["meshcat"]["a"] and window.tree["meshcat"]["a"]["c"].transform is not None
    commands = html_commands(save_html(visualizer, tmp_path / "page.html"))
    recorded = [(c["type"], c["path"]) for c in commands]
    assert recorded == [("set_object", "/meshcat/a/c"), ("set_transform", "/meshcat/a/c")]
    visualizer.close()  # no server: nothing to stop, and no error
