"""Reference solution of exercise 06 (instructors): viewing rays and their intersection with a plane."""

from __future__ import annotations

import numpy as np


def pixel_rays(K: np.ndarray, world_from_camera: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """(N, 3) unit world directions of the rays through ``pixels`` (N, 2)."""
    pixels = np.asarray(pixels, dtype=float)
    homogeneous = np.column_stack([pixels, np.ones(len(pixels))])
    in_camera = np.linalg.solve(np.asarray(K, dtype=float), homogeneous.T).T  # z = 1 in the camera frame
    in_world = in_camera @ np.asarray(world_from_camera, dtype=float)[:3, :3].T
    return in_world / np.linalg.norm(in_world, axis=1, keepdims=True)


def ray_plane_intersection(origin: np.ndarray, rays: np.ndarray, normal: np.ndarray, distance: float) -> np.ndarray:
    """(N, 3) points where the rays from ``origin`` meet ``normal @ (p - origin) == distance``; NaN where they miss."""
    origin, rays, normal = (np.asarray(a, dtype=float) for a in (origin, rays, normal))
    along = rays @ normal
    points = np.full(rays.shape, np.nan)
    hits = along > 0
    points[hits] = origin + rays[hits] * (distance / along[hits])[:, None]
    return points
