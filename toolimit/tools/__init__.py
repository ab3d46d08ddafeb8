"""Tools: the tool frame and its maths (:mod:`toolimit.tools.frame`), one record per tool
(:mod:`toolimit.tools.record`) in a registry every stage reads (:mod:`toolimit.tools.registry`), and the built-in tools, one module each.

A new tool is one :class:`ToolRecord` passed to :func:`register_tool` (its dimensions, its scene
per world, optionally its scripted motions, synthetic-demonstration generator and default robots).
"""

from toolimit.tools.frame import ToolPose, hold_last, roll_of, rotation_z, swing_rotation, tool_poses, wrap_angle
from toolimit.tools.record import PLANES, WORLDS, ToolRecord, ToolSpec
from toolimit.tools.registry import (
    TOOLS,
    find_tool,
    load_entry_point,
    register_tool,
    tool_record,
    tool_records,
    tool_spec,
)

# The built-in tools register their records on import, in the paper's order.
# isort: off
from toolimit.tools import spade, hammer, scythe  # noqa: F401, E402
# isort: on

__all__ = [
    "PLANES",
    "TOOLS",
    "WORLDS",
    "ToolPose",
    "ToolRecord",
    "ToolSpec",
    "find_tool",
    "hold_last",
    "load_entry_point",
    "register_tool",
    "roll_of",
    "rotation_z",
    "swing_rotation",
    "tool_poses",
    "tool_record",
    "tool_records",
    "tool_spec",
    "wrap_angle",
]
