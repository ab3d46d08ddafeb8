"""Scenes by name: ``make_scene(tool, world)``.

Entry points are strings ("module:Class") so that choosing a planar scene never imports the 3D
code and vice versa. Stages ask the registry; they never branch on the tool's name.
"""

from __future__ import annotations

import importlib
from typing import Any

from toolimit.errors import InputError
from toolimit.scenes.base import Scene

WORLDS = ("planar", "3d")

_ENTRY_POINTS: dict[tuple[str, str], str] = {
    ("spade", "planar"): "toolimit.scenes.planar.spade:PlanarSpadeScene",
    ("hammer", "planar"): "toolimit.scenes.planar.hammer:PlanarHammerScene",
    ("scythe", "planar"): "toolimit.scenes.planar.scythe:PlanarScytheScene",
    ("spade", "3d"): "toolimit.scenes.spatial.spade:SpatialSpadeScene",
    ("hammer", "3d"): "toolimit.scenes.spatial.hammer:SpatialHammerScene",
    ("scythe", "3d"): "toolimit.scenes.spatial.scythe:SpatialScytheScene",
}


def available_scenes() -> list[tuple[str, str]]:
    """The (tool, world) pairs that have a scene."""
    return sorted(_ENTRY_POINTS)


def register_scene(tool: str, world: str, entry_point: str) -> None:
    """Add a scene class given as "module:Class" (for researchers' own scenes)."""
    _ENTRY_POINTS[(tool, world)] = entry_point


def make_scene(tool: str, world: str, **kwargs: Any) -> Scene:
    """A new scene for ``tool`` in ``world``; keyword arguments go to its constructor."""
    if world not in WORLDS:
        raise InputError(f"unknown world {world!r}; known worlds: {', '.join(WORLDS)}")
    try:
        entry_point = _ENTRY_POINTS[(tool, world)]
    except KeyError:
        tools = sorted({t for t, w in _ENTRY_POINTS if w == world})
        raise InputError(f"unknown tool {tool!r} for world {world!r}; known tools: {', '.join(tools)}") from None
    module_name, class_name = entry_point.split(":")
    return getattr(importlib.import_module(module_name), class_name)(**kwargs)
