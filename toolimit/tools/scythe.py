"""The scythe: cut grass stalks with low sweeps."""

from toolimit.tools.record import ToolRecord, ToolSpec
from toolimit.tools.registry import register_tool

SCYTHE = ToolRecord(
    spec=ToolSpec("scythe", length=1.0, head_length=0.05, head_width=0.45),
    scenes={
        "planar": "toolimit.scenes.planar.scythe:PlanarScytheScene",
        "3d": "toolimit.scenes.spatial.scythe:SpatialScytheScene",
    },
    scripted_motions={"3d": "toolimit.scenes.spatial.sweep:scripted_sweep"},
    synthetic_motion="toolimit.demos.synthetic:scythe_knots",
    shapes="toolimit.scenes.spatial.tool_geometry:scythe_shapes",
    world_view="toolimit.viz.world_elements:scythe_elements",
    # The planar scythe's world is the horizontal x-y plane, which an arm moving in a vertical
    # plane (planar3) cannot sweep: the Panda holds that scythe.
    default_robots={"planar": "panda", "3d": "panda"},
    planar_plane="xy",
)

register_tool(SCYTHE)
