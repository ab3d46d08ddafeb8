"""Wrong on purpose: the rays are not normalised, and the intersection assumes unit rays."""

from __future__ import annotations

import numpy as np

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = ["test_ex06_rays_match_reference", "test_ex06_intersection_matches_reference"]


def pixel_rays(K, world_from_camera, pixels):
    pixels = np.asarray(pixels, dtype=float)
    rays = np.linalg.solve(K, np.column_stack([pixels, np.ones(len(pixels))]).T).T
    return rays @ np.asarray(world_from_camera)[:3, :3].T


def ray_plane_intersection(origin, rays, normal, distance):
    unit = rays / np.linalg.norm(rays, axis=1, keepdims=True)
    along = unit @ normal
    points = np.full(rays.shape, np.nan)
    hits = along > 0
    points[hits] = origin + rays[hits] * (distance / along[hits])[:, None]
    return points
