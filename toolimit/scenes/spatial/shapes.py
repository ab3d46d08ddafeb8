"""Vectorised geometry of spheres against oriented boxes and capsules (numpy, batched).

Every function broadcasts over leading dimensions, so B instances x N spheres x K shapes run as
one call without a Python loop. Frames: all inputs and outputs are in one common frame (the world
frame in the scenes) unless the name says *local* (the box's own frame: origin at its centre, axes
the columns of its rotation). Units: metres.

Signed distances are between a **point** (a sphere's centre) and the shape's surface: negative
inside. A sphere of radius r touches the shape when the distance is below r.
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.spatial.tool_geometry import ToolShapes


def to_local(points: np.ndarray, center: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Points (..., 3) expressed in the frames (center (..., 3), rotation (..., 3, 3)): R^T (p - c)."""
    return np.einsum("...j,...ja->...a", points - center, rotation)


def to_world(local: np.ndarray, center: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Inverse of :func:`to_local`: c + R q for local points (..., 3)."""
    return center + np.einsum("...aj,...j->...a", rotation, local)


def box_signed_distance(
    points: np.ndarray, center: np.ndarray, rotation: np.ndarray, half_extents: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance (...,) from points (..., 3) to oriented boxes, and the outward unit normal (..., 3).

    Outside: distance to the closest surface point, normal from that point to the point. Inside:
    minus the depth below the nearest face, normal of that face. Boxes: center (..., 3), rotation
    (..., 3, 3) (axes as columns), half_extents (..., 3); all broadcast together.
    """
    local = to_local(points, center, rotation)
    excess = np.abs(local) - half_extents  # > 0 beyond a face's plane
    outside_part = np.maximum(excess, 0.0)
    outside_distance = np.linalg.norm(outside_part, axis=-1)
    inside_depth = np.max(excess, axis=-1)  # <= 0 inside
    inside = outside_distance == 0.0
    with np.errstate(invalid="ignore", divide="ignore"):
        normal_out = np.sign(local) * outside_part / outside_distance[..., None]
    face = np.argmax(excess, axis=-1)[..., None]
    normal_in = np.where(local >= 0.0, 1.0, -1.0) * (np.arange(3) == face)
    normal_local = np.where(inside[..., None], normal_in, normal_out)
    distance = np.where(inside, inside_depth, outside_distance)
    return distance, np.einsum("...aj,...j->...a", rotation, normal_local)


def segment_closest_points(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closest points (..., 3) on segments start..end (..., 3) to points (..., 3), and their
    parameter (...,) in [0, 1] along the segment."""
    axis = end - start
    length2 = np.maximum(np.sum(axis * axis, axis=-1), 1e-18)
    t = np.clip(np.sum((points - start) * axis, axis=-1) / length2, 0.0, 1.0)
    return start + t[..., None] * axis, t


def capsule_signed_distance(
    points: np.ndarray, start: np.ndarray, end: np.ndarray, radius: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance (...,) from points (..., 3) to capsules (segment start..end (..., 3), radius)
    and the outward unit normal (..., 3).

    A point exactly on the segment is ``radius`` deep and gets the arbitrary normal +x.
    """
    closest, _ = segment_closest_points(points, start, end)
    offset = points - closest
    axis_distance = np.linalg.norm(offset, axis=-1)
    safe = np.maximum(axis_distance, 1e-12)[..., None]
    normal = np.where(axis_distance[..., None] > 1e-12, offset / safe, np.array([1.0, 0.0, 0.0]))
    return axis_distance - radius, normal


def posed_tool_shapes(shapes: ToolShapes, position: np.ndarray, rotation: np.ndarray) -> dict[str, np.ndarray]:
    """World-frame tool shapes for tool poses ``position`` (..., 3), ``rotation`` (..., 3, 3).

    Returns ``box_centers`` (..., K, 3), ``box_rotations`` (..., K, 3, 3), ``box_half_extents`` (K, 3),
    ``capsule_starts`` / ``capsule_ends`` (..., C, 3), ``capsule_radii`` (C,); metres, world frame.
    """
    position = np.asarray(position, dtype=float)[..., None, :]
    rotation = np.asarray(rotation, dtype=float)[..., None, :, :]
    return {
        "box_centers": to_world(shapes.box_centers, position, rotation),
        "box_rotations": rotation @ shapes.box_rotations,
        "box_half_extents": shapes.box_half_extents,
        "capsule_starts": to_world(shapes.capsule_starts, position, rotation),
        "capsule_ends": to_world(shapes.capsule_ends, position, rotation),
        "capsule_radii": shapes.capsule_radii,
    }
