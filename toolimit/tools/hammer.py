"""The hammer: drive a nail into a block."""

from toolimit.tools.record import ToolRecord, ToolSpec
from toolimit.tools.registry import register_tool

HAMMER = ToolRecord(
    # the authors' hammer body has its origin at the head's centre: their replay drives the head
    spec=ToolSpec("hammer", length=0.33, head_length=0.035, head_width=0.11, roll_symmetric=True, steered_point="head"),
    scenes={
        "planar": "toolimit.scenes.planar.hammer:PlanarHammerScene",
        "3d": "toolimit.scenes.spatial.hammer:SpatialHammerScene",
    },
    scripted_motions={"3d": "toolimit.scenes.spatial.strike:scripted_strike"},
    synthetic_motion="toolimit.demos.synthetic:hammer_knots",
    shapes="toolimit.scenes.spatial.tool_geometry:hammer_shapes",
    world_view="toolimit.viz.world_elements:hammer_elements",
    # the planar 3-link arm moves in the vertical x-z plane of the planar scene
    default_robots={"planar": "planar3", "3d": "panda"},
    planar_plane="xz",
)

register_tool(HAMMER)
