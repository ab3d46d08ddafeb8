"""Scenes by name: ``make_scene(tool, world)``; their hand-made solving motions: ``scripted_motion``.

Both read the tool registry (:mod:`toolimit.tools.registry`): each tool's record names its scene
class and scripted motion per world as "module:name" strings, imported only here, so that choosing
a planar scene never imports the 3D code and vice versa. Stages ask this module; they never branch
on the tool's name.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from toolimit.errors import InputError, NoScriptedMotion
from toolimit.scenes.base import CONTROL_FPS, Scene, SceneParams
from toolimit.tools.frame import ToolPose
from toolimit.tools.record import WORLDS
from toolimit.tools.registry import find_tool, load_entry_point, register_tool, tool_record, tool_records

__all__ = ["WORLDS", "available_scenes", "make_scene", "register_scene", "scene_class", "scripted_motion"]


def available_scenes() -> list[tuple[str, str]]:
    """The (tool, world) pairs that have a scene."""
    return sorted((record.name, world) for record in tool_records() for world in record.scenes)


def register_scene(tool: str, world: str, entry_point: str) -> None:
    """Give the registered ``tool`` the scene class ``entry_point`` ("module:Class") in ``world``,
    replacing the one it had (for researchers' own scenes of a known tool)."""
    check_world(world)
    record = tool_record(tool)
    register_tool(replace(record, scenes={**record.scenes, world: entry_point}), overwrite=True)


def make_scene(tool: str, world: str, **kwargs: Any) -> Scene:
    """A new scene for ``tool`` in ``world``; keyword arguments go to its constructor."""
    return scene_class(tool, world)(**kwargs)


def scene_class(tool: str, world: str) -> type[Scene]:
    """The scene class of ``tool`` in ``world`` (what :func:`make_scene` builds); InputError for a
    pair without one."""
    check_world(world)
    record = tool_record(tool)
    if world not in record.scenes:
        tools = sorted(name for name, scene_world in available_scenes() if scene_world == world)
        raise InputError(f"unknown tool {tool!r} for world {world!r}; known tools: {', '.join(tools)}")
    return load_entry_point(record.scenes[world])  # type: ignore[no-any-return]


def scripted_motion(tool: str, world: str, params: SceneParams, fps: float = CONTROL_FPS) -> ToolPose:
    """The hand-made motion of ``tool`` that solves its scene in ``world`` with ``params``: (T, 3)
    head positions (m) and (T, 3, 3) rotations, world frame, at ``fps``; NoScriptedMotion (an
    InputError) for a scene without one."""
    record = find_tool(tool)
    entry_point = None if record is None else record.scripted_motions.get(world)
    if entry_point is None:
        scripted = sorted((r.name, w) for r in tool_records() for w in r.scripted_motions)
        known = ", ".join(f"{t}/{w}" for t, w in scripted)
        raise NoScriptedMotion(f"no scripted motion for the {tool} in world {world!r}; scripted: {known}")
    return load_entry_point(entry_point)(params, fps)


def check_world(world: str) -> None:
    """InputError unless ``world`` is one of :data:`WORLDS`."""
    if world not in WORLDS:
        raise InputError(f"unknown world {world!r}; known worlds: {', '.join(WORLDS)}")
