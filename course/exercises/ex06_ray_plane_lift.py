"""Exercise 06: lifting a tracked pixel to 3D, the ray-plane intersection (stage i, from a video).

Check your work with ``python grade.py check --exercise ex06`` in the course folder (in the
project's repository: ``python course/grade.py check --exercise ex06``); see README.md. Write the
functions yourself: a submission that calls an existing implementation of them (toolimit's, a
dependency's, the course's) scores 0 for the exercise.

A calibrated camera turns a pixel into a *ray*: every world point on it projects to that pixel. One
view cannot tell how far along the ray the point is; the scene can. toolimit's lift assumes the tool
head moves in a vertical working plane facing the camera, and takes each head point as its ray's
intersection with that plane (notebook 00, ``toolimit demo lift``).
"""

from __future__ import annotations

import numpy as np


def pixel_rays(K: np.ndarray, world_from_camera: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """Return the unit directions, in the world frame, of the viewing rays through ``pixels``.

    The camera is a pinhole without distortion. Its intrinsics ``K`` (3, 3) map a point
    (x, y, z) in the camera frame to the pixel (u, v) with ``(u * z, v * z, z) = K @ (x, y, z)``;
    the camera frame has OpenCV's axes (x right, y down, z forward, the camera looks along +z).
    ``world_from_camera`` (4, 4) is the camera's pose: its 3 x 3 block R holds the camera's axes
    in the world frame as columns, its last column the camera's centre c (metres), so a camera-frame
    point p is the world point ``R @ p + c``.

    Pixels have their origin at the image's top-left corner, u to the right, v down.

    Args:
        K: (3, 3) intrinsics [[fx, s, cx], [0, fy, cy], [0, 0, 1]], pixels.
        world_from_camera: (4, 4) the camera's pose in the world.
        pixels: (N, 2) pixel coordinates (u, v).

    Returns:
        (N, 3) unit vectors: the direction from the camera's centre towards each pixel's points,
        in the world frame. Hint: which camera-frame direction has z = 1 and projects to (u, v)?
    """
    raise NotImplementedError("exercise 06: the viewing rays of pixels")


def ray_plane_intersection(origin: np.ndarray, rays: np.ndarray, normal: np.ndarray, distance: float) -> np.ndarray:
    """Return where the rays ``origin + s * rays[i]`` (s >= 0) meet a plane.

    The plane is the set of points p with ``normal @ (p - origin) == distance``: ``normal`` (3,) is
    a unit vector, ``distance`` the plane's signed distance from ``origin`` along it (metres).

    A ray that never meets the plane in front of the origin, because it runs parallel to the plane
    or points away from it (``normal @ ray <= 0``), gives a row of NaN.

    Args:
        origin: (3,) the rays' common start (the camera's centre), world frame, metres.
        rays: (N, 3) the rays' directions (not necessarily unit vectors).
        normal: (3,) the plane's unit normal.
        distance: the plane's distance from ``origin`` along ``normal``, metres.

    Returns:
        (N, 3) the intersection points, world frame, metres; NaN rows for rays that miss.
    """
    raise NotImplementedError("exercise 06: intersect rays with a plane")
