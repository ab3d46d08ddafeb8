import numpy as np
import pytest

from toolimit.demos import synthesize_demo
from toolimit.errors import DemoError, InputError, NoScriptedMotion
from toolimit.learn.shipped import environments
from toolimit.scenes import available_scenes, make_scene, register_scene
from toolimit.scenes.registry import scripted_motion
from toolimit.scenes.spatial.tool_geometry import tool_shapes
from toolimit.tools import (
    TOOLS,
    ToolPose,
    ToolRecord,
    ToolSpec,
    hold_last,
    register_tool,
    registry,
    roll_of,
    rotation_z,
    swing_rotation,
    tool_poses,
    tool_record,
    tool_spec,
)
from toolimit.viz.world_elements import world_elements


def test_swing_rotation_is_a_rotation_taking_z_to_axis():
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(200, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    axes[0] = [0, 0, -1]
    axes[1] = [0, 0, 1]
    rot = swing_rotation(axes)
    assert np.allclose(rot @ np.swapaxes(rot, 1, 2), np.eye(3), atol=1e-9)
    assert np.allclose(np.linalg.det(rot), 1.0)
    assert np.allclose(rot[:, :, 2], axes, atol=1e-9)


def test_roll_round_trip():
    rng = np.random.default_rng(1)
    head = rng.normal(size=(50, 3))
    handle = head + rng.normal(size=(50, 3))
    roll = rng.uniform(-np.pi, np.pi, 50)
    pose = tool_poses(head, handle, roll)
    assert np.allclose(roll_of(pose.rotation), roll, atol=1e-9)
    axis = (handle - head) / np.linalg.norm(handle - head, axis=1, keepdims=True)
    assert np.allclose(pose.rotation[:, :, 2], axis)


def test_unknown_tool_is_named():
    with pytest.raises(ValueError, match="unknown tool 'rake'"):
        tool_spec("rake")


def test_hold_last_repeats_the_last_pose_and_refuses_a_negative_count():
    poses = ToolPose(np.arange(6.0).reshape(2, 3), np.stack([np.eye(3), rotation_z(0.3)]))
    held = hold_last(poses, 3)
    assert held.position.shape == (5, 3) and held.rotation.shape == (5, 3, 3)
    np.testing.assert_array_equal(held.position[:2], poses.position)
    np.testing.assert_array_equal(held.position[2:], np.repeat(poses.position[-1:], 3, axis=0))
    np.testing.assert_array_equal(held.rotation[4], rotation_z(0.3))
    with pytest.raises(InputError, match="steps to hold must be >= 0, got -1"):
        hold_last(poses, -1)


# --- the tool registry ---------------------------------------------------------------------------
SCENE = "toolimit.scenes.planar.spade:PlanarSpadeScene"


@pytest.fixture
def fresh_registry(monkeypatch):
    """The tool registry as it is, restored after the test."""
    monkeypatch.setattr(registry, "_RECORDS", dict(registry._RECORDS))


def test_built_in_tools_are_registered_in_the_papers_order_with_their_dimensions():
    assert list(TOOLS) == ["spade", "hammer", "scythe"]
    assert TOOLS["hammer"] == ToolSpec("hammer", length=0.33, head_length=0.035, head_width=0.11, roll_symmetric=True, steered_point="head")
    assert tool_record("scythe").planar_plane == "xy" and tool_record("spade").planar_plane == "xz"
    assert tool_spec("spade") is tool_record("spade").spec


def test_a_registered_tool_is_seen_by_every_reader(fresh_registry):
    register_tool(
        ToolRecord(ToolSpec("rake", 1.2, 0.05, 0.4), scenes={"planar": SCENE}, default_robots={"planar": "planar3"})
    )
    assert "rake" in TOOLS and tool_spec("rake").length == 1.2
    assert ("rake", "planar") in available_scenes()
    assert make_scene("rake", "planar").tool == "spade"  # the scene class the record names
    assert ("rake", "planar") in environments()
    with pytest.raises(DemoError, match="no synthetic demonstrations for 'rake'; known: hammer, scythe, spade"):
        synthesize_demo("rake", seed=0)
    with pytest.raises(NoScriptedMotion, match="no scripted motion for the rake"):
        scripted_motion("rake", "planar", {})
    with pytest.raises(InputError, match="tool 'rake' has no 3D shapes"):
        tool_shapes("rake")
    with pytest.raises(ValueError, match="no 3D world view for tool 'rake'; known: spade, hammer, scythe"):
        world_elements("rake", {})


def test_a_taken_name_is_refused_unless_overwritten(fresh_registry):
    with pytest.raises(InputError, match="tool 'spade' is already registered"):
        register_tool(tool_record("spade"))
    register_scene("spade", "planar", "toolimit.scenes.planar.hammer:PlanarHammerScene")
    assert tool_record("spade").scenes["planar"].endswith("PlanarHammerScene")
    assert tool_record("spade").scenes["3d"].endswith("SpatialSpadeScene")


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"scenes": {}}, "a tool needs a scene in at least one world"),
        ({"scenes": {"2d": SCENE}}, "scenes: unknown world '2d'"),
        ({"scenes": {"planar": "toolimit.scenes.planar.spade"}}, r"scenes\['planar'\]: expected an entry point"),
        ({"scripted_motions": {"3d": "m:f"}}, "scripted_motions: no scene in world '3d'"),
        ({"synthetic_motion": "m:"}, "synthetic_motion: expected an entry point"),
        ({"planar_plane": "yz"}, "planar_plane must be one of xz, xy"),
        ({"shapes": "tool_geometry.spade_shapes"}, "shapes: expected an entry point"),
        ({"settings": {"3d": {"learning.timesteps": 1}}}, "settings: no scene in world '3d'"),
        ({"settings": {"planar": 5}}, r"settings\['planar'\]: expected a mapping of dotted paths"),
        ({"settings": {"planar": {"": 5}}}, r"settings\['planar'\]: expected a mapping of dotted paths"),
    ],
)
def test_a_bad_record_is_one_input_error(fields, message):
    with pytest.raises(InputError, match=message):
        ToolRecord(**{"spec": ToolSpec("rake", 1.2, 0.05, 0.4), "scenes": {"planar": SCENE}, **fields})


def test_unknown_tool_names_the_known_ones():
    with pytest.raises(InputError, match="unknown tool 'rake'; known tools: hammer, scythe, spade"):
        tool_spec("rake")
    with pytest.raises(InputError, match="unknown tool 'rake'"):
        register_scene("rake", "planar", SCENE)
