"""Cheats: the rays from the library's camera, the intersection from the library's lift."""

from toolimit.demos.video import Camera
from toolimit.demos.video.lift import ray_plane_intersection as library_intersection


def pixel_rays(K, world_from_camera, pixels):
    return Camera(1280, 720, K, world_from_camera).rays(pixels)


def ray_plane_intersection(origin, rays, normal, distance):
    return library_intersection(origin, rays, normal, distance)
