"""Wrong on purpose: a ray pointing away from the plane is 'intersected' behind the origin."""

from __future__ import annotations

import numpy as np

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = ["test_ex06_intersection_matches_reference", "test_ex06_a_hand_case"]


def pixel_rays(K, world_from_camera, pixels):
    pixels = np.asarray(pixels, dtype=float)
    rays = (
        np.linalg.solve(K, np.column_stack([pixels, np.ones(len(pixels))]).T).T
        @ np.asarray(world_from_camera)[:3, :3].T
    )
    return rays / np.linalg.norm(rays, axis=1, keepdims=True)


def ray_plane_intersection(origin, rays, normal, distance):
    along = rays @ normal
    with np.errstate(divide="ignore", invalid="ignore"):
        return origin + rays * (distance / np.where(along == 0, np.nan, along))[:, None]
