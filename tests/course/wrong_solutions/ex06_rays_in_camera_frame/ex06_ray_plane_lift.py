"""Wrong on purpose: the rays are left in the camera frame (the pose's rotation is forgotten)."""

from __future__ import annotations

import numpy as np

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = ["test_ex06_rays_match_reference", "test_ex06_the_principal_point", "test_ex06_lifting_pixels"]


def pixel_rays(K, world_from_camera, pixels):
    pixels = np.asarray(pixels, dtype=float)
    rays = np.linalg.solve(K, np.column_stack([pixels, np.ones(len(pixels))]).T).T
    return rays / np.linalg.norm(rays, axis=1, keepdims=True)


def ray_plane_intersection(origin, rays, normal, distance):
    along = rays @ normal
    points = np.full(rays.shape, np.nan)
    hits = along > 0
    points[hits] = origin + rays[hits] * (distance / along[hits])[:, None]
    return points
