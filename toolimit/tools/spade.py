"""The spade: scoop sand from a deposit and carry it into a goal box."""

from toolimit.tools.record import ToolRecord, ToolSpec
from toolimit.tools.registry import register_tool

SPADE = ToolRecord(
    spec=ToolSpec("spade", length=0.40, head_length=0.22, head_width=0.20),
    scenes={
        "planar": "toolimit.scenes.planar.spade:PlanarSpadeScene",
        "3d": "toolimit.scenes.spatial.spade:SpatialSpadeScene",
    },
    scripted_motions={
        "planar": "toolimit.scenes.planar.scoop:scripted_scoop",
        "3d": "toolimit.scenes.spatial.scoop:scripted_scoop",
    },
    synthetic_motion="toolimit.demos.synthetic:spade_knots",
    shapes="toolimit.scenes.spatial.tool_geometry:spade_shapes",
    world_view="toolimit.viz.world_elements:spade_elements",
    # the planar 3-link arm moves in the vertical x-z plane of the planar scene
    default_robots={"planar": "planar3", "3d": "panda"},
    planar_plane="xz",
)

register_tool(SPADE)
