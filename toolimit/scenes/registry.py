"""Scenes by name: ``make_scene(tool, world)``; their hand-made solving motions: ``scripted_motion``.

Entry points are strings ("module:Class") so that choosing a planar scene never imports the 3D
code and vice versa. Stages ask the registry; they never branch on the tool's name.
"""

from __future__ import annotations

import importlib
from typing import Any

from toolimit.errors import InputError, NoScriptedMotion
from toolimit.scenes.base import CONTROL_FPS, Scene, SceneParams
from toolimit.tools import ToolPose

WORLDS = ("planar", "3d")

_ENTRY_POINTS: dict[tuple[str, str], str] = {
    ("spade", "planar"): "toolimit.scenes.planar.spade:PlanarSpadeScene",
    ("hammer", "planar"): "toolimit.scenes.planar.hammer:PlanarHammerScene",
    ("scythe", "planar"): "toolimit.scenes.planar.scythe:PlanarScytheScene",
    ("spade", "3d"): "toolimit.scenes.spatial.spade:SpatialSpadeScene",
    ("hammer", "3d"): "toolimit.scenes.spatial.hammer:SpatialHammerScene",
    ("scythe", "3d"): "toolimit.scenes.spatial.scythe:SpatialScytheScene",
}

#: Hand-made tool motions that solve a scene for its parameters, without any video: the LfD
#: baseline's kinesthetic demonstrations (:mod:`toolimit.learn.kinesthetic`), tests and notebooks.
_SCRIPTED_MOTIONS: dict[tuple[str, str], str] = {
    ("spade", "planar"): "toolimit.scenes.planar.scoop:scripted_scoop",
    ("spade", "3d"): "toolimit.scenes.spatial.scoop:scripted_scoop",
    ("hammer", "3d"): "toolimit.scenes.spatial.strike:scripted_strike",
    ("scythe", "3d"): "toolimit.scenes.spatial.sweep:scripted_sweep",
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
    return _load(entry_point)(**kwargs)


def scripted_motion(tool: str, world: str, params: SceneParams, fps: float = CONTROL_FPS) -> ToolPose:
    """The hand-made motion of ``tool`` that solves its scene in ``world`` with ``params``: (T, 3)
    head positions (m) and (T, 3, 3) rotations, world frame, at ``fps``; InputError for a scene
    without one."""
    try:
        entry_point = _SCRIPTED_MOTIONS[(tool, world)]
    except KeyError:
        known = ", ".join(f"{t}/{w}" for t, w in sorted(_SCRIPTED_MOTIONS))
        raise NoScriptedMotion(f"no scripted motion for the {tool} in world {world!r}; scripted: {known}") from None
    return _load(entry_point)(params, fps)


def _load(entry_point: str) -> Any:
    """The object named by ``"module:name"``, its module imported only now."""
    module_name, name = entry_point.split(":")
    return getattr(importlib.import_module(module_name), name)
