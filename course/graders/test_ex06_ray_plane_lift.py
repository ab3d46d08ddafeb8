"""Grader of exercise 06: viewing rays and the ray-plane intersection, checked against the lift's own
``toolimit.demos.video`` (``Camera.rays``, ``ray_plane_intersection``) on seeded cameras and planes.

Each case comes from a seeded generator: the message names the seed, the camera or plane, the
input, what was expected and what you returned.
"""

from __future__ import annotations

import numpy as np
import pytest
from grading import case_seeds, check, fmt, fmt_shape

from toolimit.demos.video import look_at
from toolimit.demos.video.lift import ray_plane_intersection as reference_intersection

MODULE = "ex06_ray_plane_lift"
SEEDS = case_seeds(6)
#: Existing implementations of this exercise: a submission calling one of them gets 0 (grading.py).
#: Points of each test group (all its cases share them): 10 for the exercise.
WEIGHTS = {
    "test_ex06_rays_match_reference": 3,
    "test_ex06_the_principal_point_looks_along_the_optical_axis": 1,
    "test_ex06_intersection_matches_reference": 3,
    "test_ex06_a_hand_case": 1,
    "test_ex06_lifting_pixels_recovers_points_on_the_plane": 2,
}
#: What each function returns, for the message on a value the checks cannot read.
RETURNS = {
    "pixel_rays": "an (M, 3) float array of unit vectors in the world frame",
    "ray_plane_intersection": "an (M, 3) float array of points in metres, NaN rows where a ray misses",
}
#: Imported in the student's process before their module (it may start no thread afterwards).
STUDENT_IMPORTS = ["numpy", "toolimit.demos.video"]
FORBIDDEN = ["toolimit.demos.video"]


def random_camera(seed: int):
    """A level camera 0.5-2 m high, 2-5 m from a target near the origin, focal 400-1500 px, with a
    principal point off the image's centre and a small skew (so K is not the textbook one)."""
    rng = np.random.default_rng(seed)
    angle = rng.uniform(-np.pi, np.pi)
    reach = rng.uniform(2.0, 5.0)
    position = [reach * np.cos(angle), reach * np.sin(angle), rng.uniform(0.5, 2.0)]
    camera = look_at(position, rng.uniform(-0.3, 0.3, 3) + [0, 0, 0.5], 1280, 720, rng.uniform(400, 1500))
    K = camera.K.copy()
    K[0, 1] = rng.uniform(-2, 2)
    K[1, 1] *= rng.uniform(0.95, 1.05)
    K[:2, 2] += rng.uniform(-30, 30, 2)
    pixels = np.column_stack([rng.uniform(0, 1279, 12), rng.uniform(0, 719, 12)])
    return type(camera)(1280, 720, K, camera.world_from_camera), pixels


def describe(camera) -> str:
    return f"K = {fmt(camera.K.round(3).tolist())}, camera centre {fmt(camera.centre)} m"


@pytest.mark.parametrize("seed", SEEDS)
def test_ex06_rays_match_reference(submission, seed):
    camera, pixels = random_camera(seed)
    got = np.asarray(submission(MODULE).pixel_rays(camera.K.copy(), camera.world_from_camera.copy(), pixels.copy()))
    expected = camera.rays(pixels)
    where = f"seed {seed}, {describe(camera)}"
    check(got.shape == expected.shape, f"{where}: expected shape {expected.shape}, got {fmt_shape(got)}")
    norms = np.linalg.norm(got, axis=1)
    check(np.allclose(norms, 1.0, atol=1e-9), f"{where}: rays must be unit vectors; their lengths are {fmt(norms)}")
    worst = int(np.argmax(np.linalg.norm(got - expected, axis=1)))
    check(
        np.allclose(got, expected, atol=1e-9),
        f"{where}: pixel {fmt(pixels[worst])}: expected the world direction {fmt(expected[worst])}, got {fmt(got[worst])}",
    )


def test_ex06_the_principal_point_looks_along_the_optical_axis(submission):
    camera, _ = random_camera(0)
    got = np.asarray(submission(MODULE).pixel_rays(camera.K, camera.world_from_camera, camera.K[:2, 2][None]))
    axis = camera.world_from_camera[:3, 2]
    check(
        np.allclose(got.ravel(), axis, atol=1e-9),
        f"{describe(camera)}: the ray through the principal point {fmt(camera.K[:2, 2])} is the camera's z axis in the "
        f"world, {fmt(axis)} (the third column of world_from_camera's rotation); got {fmt(got.ravel())}",
    )


def random_plane(seed: int):
    rng = np.random.default_rng(100 + seed)
    normal = rng.normal(size=3)
    normal /= np.linalg.norm(normal)
    origin = rng.uniform(-2, 2, 3)
    rays = rng.normal(size=(15, 3)) * rng.uniform(0.5, 3.0, (15, 1))
    along = rays @ normal
    rays += np.where(along >= 0, 0.1, -0.1)[:, None] * normal  # none nearly parallel: |normal . ray| >= 0.1
    rays[:3] += (np.abs(rays[:3] @ normal) + 0.5)[:, None] * normal  # a few sure hits
    return origin, rays, normal, float(rng.uniform(0.5, 4.0))


@pytest.mark.parametrize("seed", SEEDS)
def test_ex06_intersection_matches_reference(submission, seed):
    origin, rays, normal, distance = random_plane(seed)
    got = np.asarray(submission(MODULE).ray_plane_intersection(origin.copy(), rays.copy(), normal.copy(), distance))
    expected = reference_intersection(origin, rays, normal, distance)
    where = f"seed {seed}, origin {fmt(origin)}, normal {fmt(normal)}, distance {distance:.4f} m"
    check(got.shape == expected.shape, f"{where}: expected shape {expected.shape}, got {fmt_shape(got)}")
    hits = np.all(np.isfinite(expected), axis=1)
    wrong_nan = np.flatnonzero(np.any(np.isnan(got), axis=1) != ~hits)
    if wrong_nan.size:
        i = int(wrong_nan[0])
        kind = (
            "misses the plane (parallel or pointing away): expected a row of NaN" if not hits[i] else "meets the plane"
        )
        check(False, f"{where}: ray {fmt(rays[i])} (normal . ray = {rays[i] @ normal:.4f}) {kind}; got {fmt(got[i])}")
    error = np.linalg.norm(got[hits] - expected[hits], axis=1)
    worst = int(np.argmax(error))
    check(
        np.all(error < 1e-9),
        f"{where}: ray {fmt(rays[hits][worst])}: expected the point {fmt(expected[hits][worst])}, got {fmt(got[hits][worst])}",
    )


def test_ex06_a_hand_case(submission):
    got = np.asarray(
        submission(MODULE).ray_plane_intersection(
            np.array([1.0, 2.0, 3.0]),
            np.array([[1.0, 0.0, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0], [-2.0, 0.0, 0.0]]),
            np.array([1.0, 0.0, 0.0]),
            2.0,
        )
    )
    expected = np.array([[3.0, 2.0, 3.0], [3.0, 2.0 + 8.0 / 3.0, 3.0]])
    message = (
        "origin (1, 2, 3), plane x = 3 (normal (1, 0, 0), distance 2): the ray (1, 0, 0) meets it at (3, 2, 3), "
        "(0.6, 0.8, 0) at (3, 4.6667, 3); (0, 0, 1) runs parallel to it and (-2, 0, 0) points away: NaN rows. "
        f"You returned {fmt(got.tolist())}"
    )
    check(got.shape == (4, 3), message)
    check(np.allclose(got[:2], expected, atol=1e-12) and np.all(np.isnan(got[2:])), message)


@pytest.mark.parametrize("seed", SEEDS)
def test_ex06_lifting_pixels_recovers_points_on_the_plane(submission, seed):
    """The lift: points on a vertical plane facing the camera, projected, then lifted back."""
    camera, _ = random_camera(seed)
    rng = np.random.default_rng(200 + seed)
    forward = camera.world_from_camera[:3, 2] * [1.0, 1.0, 0.0]
    normal = forward / np.linalg.norm(forward)
    across = np.cross([0.0, 0.0, 1.0], normal)
    distance = float(rng.uniform(2.0, 4.0))
    points = camera.centre + distance * normal + np.outer(rng.uniform(-1, 1, 10), across)
    points[:, 2] = rng.uniform(0.0, 1.2, 10)
    pixels, _ = camera.project(points)
    student = submission(MODULE)
    rays = np.asarray(student.pixel_rays(camera.K, camera.world_from_camera, pixels))
    got = np.asarray(student.ray_plane_intersection(camera.centre, rays, normal, distance))
    error = np.linalg.norm(got - points, axis=1)
    worst = int(np.nanargmax(error)) if np.any(np.isfinite(error)) else 0
    check(
        np.all(error < 1e-7),
        f"seed {seed}, {describe(camera)}, plane {distance:.3f} m away along {fmt(normal)}: pixel {fmt(pixels[worst])} "
        f"came from {fmt(points[worst])}; your rays and intersection give {fmt(got[worst])}",
    )
