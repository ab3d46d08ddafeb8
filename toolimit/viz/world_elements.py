"""What a 3D world looks like at one instant: boxes and spheres read from a scene snapshot.

One neutral description shared by the meshcat views and the rerun recordings, so that both draw
the same things. World frame: metres, z up, ground z = 0. ``world_elements(tool, snapshot)`` draws
with the function the tool's record names (``ToolRecord.world_view``), which knows the
``snapshot()`` keys of its 3D world: :func:`spade_elements`, :func:`hammer_elements`,
:func:`scythe_elements` for instance 0 of ``SpatialSpadeScene``, ``SpatialHammerScene``,
``SpatialScytheScene``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np

from toolimit.tools.frame import rotation_z
from toolimit.tools.registry import find_tool, load_entry_point, tool_records

#: Side of the square ground tile drawn under every world, m.
GROUND_SIZE = 4.0


@dataclass(frozen=True)
class Element:
    """One drawn part of a world at one instant.

    Attributes:
        path: slash-separated name, stable across frames ("nail/plate", "stalks/3"); the first
            component is its group.
        shape: "box" or "sphere".
        size: (3,) half extents of a box or (1,) radius of a sphere, m.
        colour: (4,) RGBA in 0..1.
        transform: (4, 4) world placement of the shape's centre (rotation = box axes as columns).
    """

    path: str
    shape: Literal["box", "sphere"]
    size: np.ndarray
    colour: tuple[float, float, float, float]
    transform: np.ndarray

    @property
    def group(self) -> str:
        """The first component of ``path``."""
        return self.path.split("/")[0]


def placement(center: np.ndarray, rotation: np.ndarray | None = None) -> np.ndarray:
    """(4, 4) homogeneous transform from a centre (3,) and a rotation (3, 3) (identity if None)."""
    transform = np.eye(4)
    transform[:3, 3] = center
    if rotation is not None:
        transform[:3, :3] = rotation
    return transform


def _box(path: str, center, half_extents, colour, rotation=None) -> Element:
    return Element(path, "box", np.asarray(half_extents, dtype=float), colour, placement(center, rotation))


def _ground(center_xy: np.ndarray) -> Element:
    half = [GROUND_SIZE / 2, GROUND_SIZE / 2, 0.005]
    return _box("ground", [center_xy[0], center_xy[1], -0.005], half, (0.85, 0.85, 0.8, 1.0))


def hammer_elements(snapshot: Mapping[str, np.ndarray]) -> list[Element]:
    """Board, nail head plate and shank."""
    steel = (0.45, 0.45, 0.5, 1.0)
    return [
        _ground(snapshot["board_center"][:2]),
        _box("board", snapshot["board_center"], snapshot["board_half_extents"], (0.72, 0.55, 0.35, 1.0)),
        _box("nail/plate", snapshot["plate_center"], snapshot["plate_half_extents"], steel),
        _box("nail/shank", snapshot["shank_center"], snapshot["shank_half_extents"], steel),
    ]


#: A cut stalk lies on the ground: its own z axis along world y.
_FALLEN = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def scythe_elements(snapshot: Mapping[str, np.ndarray]) -> list[Element]:
    """Patch and stalks; cut stalks lie on the ground (straw coloured)."""
    center, yaw = snapshot["patch_center"], float(snapshot["patch_yaw"])
    turn = rotation_z(yaw)
    half = snapshot["stalk_half_extents"]
    patch_half = [*snapshot["patch_half_extents"], 0.001]
    elements = [
        _ground(center[:2]),
        _box("patch", center + [0.0, 0.0, 0.001], patch_half, (0.45, 0.35, 0.2, 1.0), turn),
    ]
    for i, (base, cut) in enumerate(zip(snapshot["stalk_base"], snapshot["stalk_cut"])):
        if cut:
            elements.append(_box(f"stalks/{i}", base + [0.0, half[2], half[0]], half, (0.75, 0.7, 0.2, 1.0), _FALLEN))
        else:
            elements.append(_box(f"stalks/{i}", base + [0.0, 0.0, half[2]], half, (0.2, 0.7, 0.2, 1.0)))
    return elements


def spade_elements(snapshot: Mapping[str, np.ndarray]) -> list[Element]:
    """Deposit and goal-box walls, sand spheres."""
    elements = [_ground(snapshot["goal_position"][:2])]
    walls = zip(snapshot["wall_centers"], snapshot["wall_rotations"], snapshot["wall_half_extents"])
    for i, (center, rotation, half) in enumerate(walls):
        elements.append(_box(f"walls/{i}", center, half, (0.6, 0.6, 0.65, 0.6), rotation))
    radius = np.array([float(snapshot["sphere_radius"])])
    for i, position in enumerate(snapshot["sphere_positions"]):
        elements.append(Element(f"sand/{i}", "sphere", radius, (0.85, 0.7, 0.4, 1.0), placement(position)))
    return elements


def world_elements(tool: str, snapshot: Mapping[str, np.ndarray]) -> list[Element]:
    """The drawn parts of the 3D world of ``tool`` in the state ``snapshot``.

    Raises ValueError for an unknown tool or a snapshot without a key the world needs.
    """
    record = find_tool(tool)
    if record is None or record.world_view is None:
        known = ", ".join(r.name for r in tool_records() if r.world_view is not None)
        raise ValueError(f"no 3D world view for tool {tool!r}; known: {known}")
    try:
        return load_entry_point(record.world_view)(snapshot)
    except KeyError as error:
        raise ValueError(f"{tool} snapshot lacks the key {error.args[0]!r}") from None
