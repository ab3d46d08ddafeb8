"""Collision and display geometry of the tools (spade, hammer, scythe) in the tool frame.

Every shape is placed in the **tool frame** of :mod:`toolimit.tools`: origin at the head point, z
from the head towards the handle end (the handle end, where a robot holds the tool, is at
``(0, 0, ToolSpec.length)``), x the working direction. Units: metres.

One description, two forms (:func:`tool_shapes` returns both, built from the same numbers):

* plain numpy oriented boxes and capsules (:class:`OrientedBox`, :class:`Capsule`, and the stacked
  arrays of :class:`ToolShapes`) for the vectorised contact code of the 3D scenes;
* a Pinocchio ``GeometryModel`` of coal shapes (``coal.Box``, ``coal.Capsule``) with colours, for
  meshcat views and for collision queries with robot models. Its objects hang on the universe joint
  with placements in the tool frame: to show the tool at a world pose ``T``, compose ``T *
  placement``.

The shapes:

* **spade**: a flat blade ``SPADE_BLADE_WIDTH`` (0.17 m, across, tool y) by ``SPADE_BLADE_LENGTH``
  (0.12 m, along z from the tip) whose carrying face is the plane x = 0 with normal +x (the plate lies at x < 0);
  a rim of thin walls standing ``SPADE_RIM_HEIGHT`` on the carrying face along both sides and the
  back (the end towards the handle), open at the tip, so that sand stays on the face; a socket
  strap behind the blade and a handle capsule on the tool axis from the blade's back to 6 cm beyond
  the handle end (0.41 m of handle with the socket).
* **hammer**: a head box ``head_width`` (0.11 m) along x (striking faces at x = +-0.055, normal
  +x on the working side), ``head_length`` (0.035 m) along z, 0.03 m across y, centred on the head
  point; a handle capsule along z to 3 cm beyond the handle end.
* **scythe** (the authors' ``ScytheTool``): a blade along +x, ``head_width`` (0.35 m) long, from
  the snath's side (``SCYTHE_SNATH_RADIUS``, 2 cm from the axis), ``head_length`` (0.04 m) along z
  centred on the head point, 1 cm thick across y; a snath capsule (radius 2 cm) along z from the
  blade's far side (the authors' 0.70 m snath) to 3 cm beyond the handle end, where a robot grips. The cutting edge is the blade's side towards the
  handle (z = +0.02 m), facing +z (:mod:`toolimit.scenes.scythe_cut`).

The working part is always the first box (``tool_boxes(name)[0]``): the spade blade plate, the
hammer head, the scythe blade. Each tool's record names its builder (``ToolRecord.shapes``,
:mod:`toolimit.tools.registry`): :func:`spade_shapes`, :func:`hammer_shapes`, :func:`scythe_shapes`.
"""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from toolimit.errors import InputError
from toolimit.tools.registry import load_entry_point, tool_record, tool_spec
from toolimit.tools.scythe import SCYTHE_SNATH_RADIUS

#: The 3D spade blade (m): length along the tool axis from the tip, width across (tool y). The
#: original scene's spade mesh has a blade of about 0.17 m x 0.12 m; of the two ways to read it,
#: 0.12 m along the axis and 0.17 m across carries more sand on the authors' own aligned motions
#: (10 replays each, 200 spheres: mean goal reward 9.3 and 7.8 against 6.8 and 5.3 the other way
#: round), so the 3D world uses it. ``ToolSpec.head_length`` / ``head_width`` (0.22 m x 0.20 m)
#: stay the planar world's dustpan cross-section, whose sand circles it is sized for.
SPADE_BLADE_LENGTH = 0.12
SPADE_BLADE_WIDTH = 0.17
#: Height of the spade's rim walls above the carrying face (m).
SPADE_RIM_HEIGHT = 0.05
#: Thickness of the spade blade plate and of its rim walls (m).
SPADE_PLATE_THICKNESS = 0.006
#: Radius of the spade handle (m).
SPADE_HANDLE_RADIUS = 0.016
#: Radius of the hammer handle (m).
HAMMER_HANDLE_RADIUS = 0.014
#: Thickness of the scythe blade across the tool y axis (m), the authors' ``blade_height``.
SCYTHE_BLADE_THICKNESS = 0.01

#: RGBA colours for views (0..1).
COLOURS = {
    "steel": np.array([0.62, 0.64, 0.68, 1.0]),
    "dark_steel": np.array([0.30, 0.31, 0.34, 1.0]),
    "wood": np.array([0.55, 0.36, 0.20, 1.0]),
    "blade_green": np.array([0.20, 0.50, 0.30, 1.0]),
}


@dataclass(frozen=True)
class OrientedBox:
    """A box in the tool frame.

    Attributes:
        name: unique within the tool ("blade", "rim_left", ...).
        center: (3,) centre, tool frame, m.
        rotation: (3, 3) box axes as columns, tool frame.
        half_extents: (3,) half sizes along the box's own axes, m.
        colour: (4,) RGBA for views.
    """

    name: str
    center: np.ndarray
    rotation: np.ndarray
    half_extents: np.ndarray
    colour: np.ndarray


@dataclass(frozen=True)
class Capsule:
    """A capsule (segment swept by a ball) in the tool frame.

    Attributes:
        name: unique within the tool.
        center: (3,) middle of the segment, tool frame, m.
        rotation: (3, 3) the capsule's axis is the third column (its local z), tool frame.
        half_length: half of the segment's length, m (coal's ``halfLength``).
        radius: m.
        colour: (4,) RGBA.
    """

    name: str
    center: np.ndarray
    rotation: np.ndarray
    half_length: float
    radius: float
    colour: np.ndarray

    @property
    def endpoints(self) -> tuple[np.ndarray, np.ndarray]:
        """The segment's two ends (3,), tool frame, m: centre -+ half_length along the axis."""
        axis = self.rotation[:, 2] * self.half_length
        return self.center - axis, self.center + axis


@dataclass(frozen=True)
class ToolShapes:
    """All shapes of one tool: per-shape objects, stacked arrays, and the Pinocchio model.

    Attributes:
        tool: tool name.
        boxes: the boxes; ``boxes[0]`` is the working part.
        capsules: the capsules (handles).
        box_centers: (K, 3) tool frame, m.
        box_rotations: (K, 3, 3) box axes as columns, tool frame.
        box_half_extents: (K, 3) m.
        capsule_starts, capsule_ends: (C, 3) segment ends, tool frame, m.
        capsule_radii: (C,) m.
        geometry_model: ``pin.GeometryModel`` with one ``pin.GeometryObject`` per shape (same order:
            boxes then capsules), named ``"<tool>/<shape>"``, on joint 0 with tool-frame placements.
    """

    tool: str
    boxes: tuple[OrientedBox, ...]
    capsules: tuple[Capsule, ...]
    box_centers: np.ndarray
    box_rotations: np.ndarray
    box_half_extents: np.ndarray
    capsule_starts: np.ndarray
    capsule_ends: np.ndarray
    capsule_radii: np.ndarray
    geometry_model: pin.GeometryModel


def _box(name: str, low: tuple[float, float, float], high: tuple[float, float, float], colour: str) -> OrientedBox:
    """An axis-aligned box spanning ``low``..``high`` (tool frame, m)."""
    low_arr, high_arr = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    return OrientedBox(name, (low_arr + high_arr) / 2, np.eye(3), (high_arr - low_arr) / 2, COLOURS[colour])


def _capsule_along_z(name: str, z_start: float, z_end: float, radius: float, colour: str) -> Capsule:
    """A capsule on the tool axis whose segment runs from z_start to z_end (m)."""
    return Capsule(
        name, np.array([0.0, 0.0, (z_start + z_end) / 2]), np.eye(3), (z_end - z_start) / 2, radius, COLOURS[colour]
    )


def spade_shapes() -> tuple[list[OrientedBox], list[Capsule]]:
    """The spade's boxes (the working part first) and capsules (see the module docstring)."""
    spec = tool_spec("spade")
    t, rim, w, blade = SPADE_PLATE_THICKNESS, SPADE_RIM_HEIGHT, SPADE_BLADE_WIDTH / 2, SPADE_BLADE_LENGTH
    boxes = [
        _box("blade", (-t, -w, 0.0), (0.0, w, blade), "steel"),
        _box("rim_left", (0.0, w - t, 0.0), (rim, w, blade), "steel"),
        _box("rim_right", (0.0, -w, 0.0), (rim, -w + t, blade), "steel"),
        _box("rim_back", (-t, -w, blade - t), (rim, w, blade), "steel"),
        _box("socket", (-t - 0.016, -0.02, 0.05), (-t, 0.02, blade), "dark_steel"),
    ]
    r = SPADE_HANDLE_RADIUS
    capsules = [_capsule_along_z("handle", blade + r, spec.length + 0.06 - r, r, "wood")]
    return boxes, capsules


def hammer_shapes() -> tuple[list[OrientedBox], list[Capsule]]:
    """The hammer's boxes (the working part first) and capsules (see the module docstring)."""
    spec = tool_spec("hammer")
    x, z, y = spec.head_width / 2, spec.head_length / 2, 0.015
    boxes = [_box("head", (-x, -y, -z), (x, y, z), "dark_steel")]
    r = HAMMER_HANDLE_RADIUS
    capsules = [_capsule_along_z("handle", z, spec.length + 0.03 - r, r, "wood")]
    return boxes, capsules


def scythe_shapes() -> tuple[list[OrientedBox], list[Capsule]]:
    """The scythe's boxes (the working part first) and capsules (see the module docstring)."""
    spec = tool_spec("scythe")
    r, y, z = SCYTHE_SNATH_RADIUS, SCYTHE_BLADE_THICKNESS / 2, spec.head_length / 2
    boxes = [_box("blade", (r, -y, -z), (r + spec.head_width, y, z), "steel")]
    capsules = [_capsule_along_z("snath", -z + r, spec.length + 0.03 - r, r, "wood")]
    return boxes, capsules


def tool_boxes(tool: str) -> tuple[OrientedBox, ...]:
    """The boxes of ``tool`` in its tool frame; the first is the working part."""
    return tool_shapes(tool).boxes


def tool_shapes(tool: str) -> ToolShapes:
    """Boxes, capsules, stacked arrays and the Pinocchio ``GeometryModel`` of ``tool``.

    Raises ValueError (InputError) for an unknown tool name or a tool whose record names no
    ``shapes``. A new object each call (the GeometryModel is mutable), cheap enough to call once
    per scene.
    """
    entry_point = tool_record(tool).shapes
    if entry_point is None:
        raise InputError(f"tool {tool!r} has no 3D shapes (its ToolRecord.shapes is None)")
    boxes, capsules = load_entry_point(entry_point)()
    model = pin.GeometryModel()
    for box in boxes:
        obj = pin.GeometryObject(
            f"{tool}/{box.name}", 0, 0, pin.SE3(box.rotation, box.center), coal.Box(*(2 * box.half_extents))
        )
        obj.meshColor = box.colour
        model.addGeometryObject(obj)
    for capsule in capsules:
        obj = pin.GeometryObject(
            f"{tool}/{capsule.name}",
            0,
            0,
            pin.SE3(capsule.rotation, capsule.center),
            coal.Capsule(capsule.radius, 2 * capsule.half_length),
        )
        obj.meshColor = capsule.colour
        model.addGeometryObject(obj)
    starts, ends = zip(*(c.endpoints for c in capsules)) if capsules else ((), ())
    return ToolShapes(
        tool=tool,
        boxes=tuple(boxes),
        capsules=tuple(capsules),
        box_centers=np.array([b.center for b in boxes]).reshape(-1, 3),
        box_rotations=np.array([b.rotation for b in boxes]).reshape(-1, 3, 3),
        box_half_extents=np.array([b.half_extents for b in boxes]).reshape(-1, 3),
        capsule_starts=np.array(starts).reshape(-1, 3),
        capsule_ends=np.array(ends).reshape(-1, 3),
        capsule_radii=np.array([c.radius for c in capsules]),
        geometry_model=model,
    )
