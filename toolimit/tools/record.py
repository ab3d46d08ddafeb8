"""What toolimit knows about one tool: its dimensions (:class:`ToolSpec`) and everything each stage
needs to find for it (:class:`ToolRecord`), written once in the tool's own module.

Code is named by ``"module:name"`` entry-point strings, imported only when a stage asks for it, so
that registering a tool imports no scene or generator code and choosing a planar scene never
imports the 3D code.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Literal

from toolimit.errors import InputError

#: The worlds a scene can live in: a plane (pymunk) or 3D (batched particles).
WORLDS = ("planar", "3d")
#: The planes a planar scene can live in: "xz" the vertical plane, "xy" the horizontal one.
PLANES = ("xz", "xy")


@dataclass(frozen=True)
class ToolSpec:
    """Dimensions of a tool, metres, in its tool frame (:mod:`toolimit.tools.frame`).

    Attributes:
        name: registry name.
        length: head point to handle end (where a robot flange holds it).
        head_length: extent of the working part along the tool axis from the head point
            (spade blade length, hammer head height, scythe blade root block).
        head_width: extent of the working part across the tool (spade blade width, hammer head
            length along its striking axis, scythe blade length along x).
        roll_symmetric: True when a roll of pi about the tool axis gives an equivalent tool.
        steered_point: the point whose speed the tool-alone replay caps
            (:func:`toolimit.scenes.replay.speed_limited`): ``"handle"`` the handle end, ``"head"``
            the head point; the origin of the authors' tool body, which their replay drives.
    """

    name: str
    length: float
    head_length: float
    head_width: float
    roll_symmetric: bool = False
    steered_point: Literal["handle", "head"] = "handle"

    @property
    def steered_offset(self) -> float:
        """Distance (m) from the head point along the tool's z axis to ``steered_point``."""
        return self.length if self.steered_point == "handle" else 0.0


@dataclass(frozen=True)
class ToolRecord:
    """One tool, as every stage finds it (:func:`toolimit.tools.register_tool`).

    Attributes:
        spec: the tool's dimensions; ``spec.name`` is the tool's registry name.
        scenes: world ("planar" or "3d") -> ``"module:Class"`` of the scene class (a
            :class:`toolimit.scenes.Scene`, built with the scene's keyword arguments).
        scripted_motions: world -> ``"module:function"`` of a hand-made motion solving the scene,
            ``function(params, fps) -> ToolPose`` (world frame, metres; the LfD baseline's
            kinesthetic demonstrations, tests). Optional.
        synthetic_motion: ``"module:function"`` of the synthetic-demonstration generator,
            ``function(rng, fps) -> (knots, points, events, params)`` (see
            :mod:`toolimit.demos.synthetic`), or None for a tool without synthetic demonstrations.
        default_robots: world -> the robot that holds the tool there when none is asked for (the
            robot of the shipped learning task, :mod:`toolimit.learn.shipped`); a world listed here
            gets a registered Gymnasium id ``toolimit/<Tool><World>-v0``.
        planar_plane: the plane of the tool's planar scene (one of :data:`PLANES`), onto which
            alignment projects the demonstration.
        shapes: ``"module:function"`` of the tool's 3D shapes in its tool frame,
            ``function() -> (boxes, capsules)`` (:mod:`toolimit.scenes.spatial.tool_geometry`), for
            3D contacts and views; None for a tool without them.
        world_view: ``"module:function"`` drawing the state of its 3D scene,
            ``function(snapshot) -> list[Element]`` (:mod:`toolimit.viz.world_elements`); None for
            a tool without 3D views.
        settings: world -> the tool's own pipeline settings there, by dotted path into
            :class:`~toolimit.pipeline.settings.PipelineSettings` (``{"learning.timesteps":
            14_000_000}``), over the world's preset (:meth:`PipelineSettings.for_world`): what a
            tool needs beyond the other tools, measured.
    """

    spec: ToolSpec
    scenes: Mapping[str, str]
    scripted_motions: Mapping[str, str] = field(default_factory=dict)
    synthetic_motion: str | None = None
    default_robots: Mapping[str, str] = field(default_factory=dict)
    planar_plane: str = "xz"
    shapes: str | None = None
    world_view: str | None = None
    settings: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        """Checks every field (InputError naming the bad one) and freezes the mappings."""
        if not isinstance(self.spec, ToolSpec):
            raise InputError(f"ToolRecord.spec must be a ToolSpec, got {type(self.spec).__name__}")
        name = self.spec.name
        for world, values in self.settings.items():
            if not isinstance(values, Mapping) or not all(isinstance(path, str) and path for path in values):
                raise InputError(f"tool {name!r}: settings[{world!r}]: expected a mapping of dotted paths to values")
        frozen = {world: MappingProxyType(dict(values)) for world, values in self.settings.items()}
        object.__setattr__(self, "settings", frozen)
        for attribute in ("scenes", "scripted_motions", "default_robots", "settings"):
            mapping = getattr(self, attribute)
            unknown = sorted(set(mapping) - set(WORLDS))
            if unknown:
                raise InputError(
                    f"tool {name!r}: {attribute}: unknown world {unknown[0]!r}; known: {', '.join(WORLDS)}"
                )
            object.__setattr__(self, attribute, MappingProxyType(dict(mapping)))
        if not self.scenes:
            raise InputError(f"tool {name!r}: scenes: a tool needs a scene in at least one world")
        for attribute in ("scripted_motions", "default_robots", "settings"):
            without_scene = sorted(set(getattr(self, attribute)) - set(self.scenes))
            if without_scene:
                raise InputError(f"tool {name!r}: {attribute}: no scene in world {without_scene[0]!r}")
        for what, entry_point in [
            *((f"scenes[{w!r}]", e) for w, e in self.scenes.items()),
            *((f"scripted_motions[{w!r}]", e) for w, e in self.scripted_motions.items()),
            ("synthetic_motion", self.synthetic_motion),
            ("shapes", self.shapes),
            ("world_view", self.world_view),
        ]:
            if entry_point is not None:
                check_entry_point(entry_point, f"tool {name!r}: {what}")
        if self.planar_plane not in PLANES:
            raise InputError(
                f"tool {name!r}: planar_plane must be one of {', '.join(PLANES)}, got {self.planar_plane!r}"
            )

    @property
    def name(self) -> str:
        """The registry name (``spec.name``)."""
        return self.spec.name


def check_entry_point(entry_point: str, what: str) -> None:
    """InputError naming ``what`` unless ``entry_point`` has the form ``"module:name"``."""
    if not isinstance(entry_point, str) or entry_point.count(":") != 1 or "" in entry_point.split(":"):
        raise InputError(f"{what}: expected an entry point 'module:name', got {entry_point!r}")
