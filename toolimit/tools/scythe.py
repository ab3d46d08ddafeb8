"""The scythe: cut grass stalks with low sweeps.

Dimensions are the authors' (pyphysx_envs ``tools/ScytheTool.py``): a 0.35 m blade, 0.04 m wide
along the snath and 1 cm thick, at the end of a 0.70 m snath (twice the blade), sticking out
sideways from it. The tool frame's head point is the authors' tool tip: on the snath's axis at the
blade's mid-width, 0.68 m from the snath's far end (their ``tool_length``), where the robot holds it.
"""

from toolimit.tools.record import ToolRecord, ToolSpec
from toolimit.tools.registry import register_tool

#: Radius of the snath (m): half the authors' 0.04 m handle width. The blade starts at its side.
SCYTHE_SNATH_RADIUS = 0.02

SCYTHE = ToolRecord(
    spec=ToolSpec("scythe", length=0.68, head_length=0.04, head_width=0.35),
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
    # PPO's budget in 3D: the authors' own (train_ppo.py: 10,000 updates of 35 x 2 episodes of the
    # 20-step cut episode, 14 M steps). All 10 stalks, scattered anew at every reset, take PPO far
    # longer than the other tools' goals: scythe_02's policy succeeds at 4.3 M, scythe_04's reaches
    # 0.70 at 14 M (seed 0), where the spade's and the hammer's succeed within 1.5 M. Early stopping
    # ends a run that succeeds.
    settings={"3d": {"learning.timesteps": 14_000_000}},
)

register_tool(SCYTHE)
