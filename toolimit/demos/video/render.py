"""A demonstration filmed by a camera, as an MP4: the tool as a coloured stick with a marker on each
end, a ground grid, and a standing figure between the camera and part of the motion (it hides the
tool in some frames, as a demonstrator's body would). Needs OpenCV (the ``[video]`` extra).

The markers are the tracker's targets (:mod:`.marker_tracking`): a red disc on the head, a blue
disc on the handle end, drawn with sub-pixel centres so that a tracked centre can match the true
projection well under a pixel.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import cv2
import numpy as np

from toolimit.artifacts import atomic_path
from toolimit.demos.tool_demo import ToolDemo
from toolimit.demos.video.camera import Camera
from toolimit.demos.video.tracks import EndpointTracks, project_demo
from toolimit.errors import TrackError


@dataclass(frozen=True)
class Marker:
    """A disc drawn on one end of the tool.

    Attributes:
        bgr: its colour (OpenCV's blue, green, red order, 0-255).
        hue: its hue range on OpenCV's 0-179 scale (low > high wraps around red).
        radius: its radius, pixels (whatever the end's distance: a painted marker would shrink,
            a tracked keypoint does not).
    """

    bgr: tuple[int, int, int]
    hue: tuple[int, int]
    radius: int = 8


HEAD_MARKER = Marker(bgr=(0, 0, 255), hue=(172, 8))
HANDLE_MARKER = Marker(bgr=(255, 0, 0), hue=(110, 130))
#: The stick (yellow), the sky, the ground and its grid lines, the figure (low saturation: never a marker's colour).
STICK_BGR, SKY_BGR, GROUND_BGR, GRID_BGR, FIGURE_BGR = (
    (40, 200, 230),
    (235, 225, 215),
    (150, 165, 150),
    (95, 105, 95),
    (70, 70, 75),
)
#: Grid spacing and half-size around the motion, metres; the figure's height and width, metres.
GRID_STEP, GRID_HALF_SIZE, FIGURE_HEIGHT, FIGURE_WIDTH = 0.5, 4.0, 1.7, 0.4
#: The figure hides this share of the head's image x range, at its right end.
FIGURE_OVERLAP = 0.05
#: OpenCV's sub-pixel drawing: coordinates in 1/16 px.
_SHIFT = 4


def render_video(demo: ToolDemo, camera: Camera, path: str | os.PathLike[str]) -> EndpointTracks:
    """Film ``demo`` with ``camera`` to the MP4 at ``path`` (written atomically, ``demo.fps``
    frames per second) and return the true tracks: an end is visible when its centre is in the
    image and not behind the figure."""
    background = _background(camera, demo)
    figure = _figure_mask(camera, demo)
    truth = project_demo(demo, camera)
    _, head_depth = camera.project(demo.head)
    _, handle_depth = camera.project(demo.handle)
    with atomic_path(path) as tmp:
        writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter.fourcc(*"mp4v"), demo.fps, (camera.width, camera.height))
        if not writer.isOpened():
            raise TrackError(f"{path}: OpenCV cannot write an MP4 video here")
        try:
            for t in range(demo.n_frames):
                image = background.copy()
                ends = [(truth.head[t], head_depth[t], HEAD_MARKER), (truth.handle[t], handle_depth[t], HANDLE_MARKER)]
                if head_depth[t] > 0 and handle_depth[t] > 0:
                    cv2.line(image, _fixed(ends[0][0]), _fixed(ends[1][0]), STICK_BGR, 5, cv2.LINE_AA, _SHIFT)
                for point, depth, marker in sorted(ends, key=lambda end: -end[1]):  # the farther end first
                    if depth > 0:
                        cv2.circle(image, _fixed(point), marker.radius << _SHIFT, marker.bgr, -1, cv2.LINE_AA, _SHIFT)
                image[figure] = FIGURE_BGR
                writer.write(image)
        finally:
            writer.release()
    hidden = {name: _covered(figure, getattr(truth, name)) for name in ("head", "handle")}
    return EndpointTracks(
        truth.head,
        truth.handle,
        truth.head_visible & ~hidden["head"],
        truth.handle_visible & ~hidden["handle"],
    )


def _fixed(pixel: np.ndarray) -> tuple[int, int]:
    """A pixel (u, v) in OpenCV's fixed point (1/16 px), clamped far outside the image."""
    clamped = np.clip(np.nan_to_num(pixel), -1e5, 1e5)
    return int(round(clamped[0] * (1 << _SHIFT))), int(round(clamped[1] * (1 << _SHIFT)))


def _covered(mask: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """(T,) whether each pixel (T, 2) falls on ``mask`` (outside the image: not covered)."""
    covered = np.zeros(len(pixels), dtype=bool)
    with np.errstate(invalid="ignore"):
        rounded = np.round(np.nan_to_num(pixels, nan=-1.0)).astype(int)
    inside = (
        (rounded[:, 0] >= 0) & (rounded[:, 0] < mask.shape[1]) & (rounded[:, 1] >= 0) & (rounded[:, 1] < mask.shape[0])
    )
    covered[inside] = mask[rounded[inside, 1], rounded[inside, 0]]
    return covered


def _background(camera: Camera, demo: ToolDemo) -> np.ndarray:
    """The still image: sky, the ground where the pixel's ray meets it, the grid lines around the motion."""
    rows, cols = np.mgrid[0 : camera.height, 0 : camera.width]
    rays = camera.rays(np.column_stack([cols.ravel(), rows.ravel()]))
    ground = (rays[:, 2] < 0).reshape(camera.height, camera.width)
    image = np.empty((camera.height, camera.width, 3), dtype=np.uint8)
    image[:] = SKY_BGR
    image[ground] = GROUND_BGR
    centre = np.round(demo.head.mean(axis=0)[:2] / GRID_STEP) * GRID_STEP
    steps = np.arange(-GRID_HALF_SIZE, GRID_HALF_SIZE + 1e-9, GRID_STEP)
    along = np.linspace(-GRID_HALF_SIZE, GRID_HALF_SIZE, 200)
    for offset in steps:
        for axis in (0, 1):
            points = np.zeros((len(along), 3))
            points[:, axis] = centre[axis] + along
            points[:, 1 - axis] = centre[1 - axis] + offset
            pixels, depth = camera.project(points)
            front = depth > 0.2
            if np.sum(front) >= 2:
                polyline = np.round(pixels[front] * (1 << _SHIFT)).astype(np.int32)
                cv2.polylines(image, [polyline], False, GRID_BGR, 1, cv2.LINE_AA, _SHIFT)
    return image


def _figure_mask(camera: Camera, demo: ToolDemo) -> np.ndarray:
    """(height, width) bool: a standing figure (body and head) on the ground, 0.6 m nearer the camera
    than the motion, its left edge at ``FIGURE_OVERLAP`` of the head's image x range from its right
    end, so that it hides the tool at one end of the motion."""
    from toolimit.demos.video.lift import ray_plane_intersection

    pixels, _ = camera.project(demo.head)
    u_low, u_high = np.nanmin(pixels[:, 0]), np.nanmax(pixels[:, 0])
    normal = camera.rotation[:, 2] * [1.0, 1.0, 0.0]
    normal /= np.linalg.norm(normal)
    distance = float(normal @ (demo.head.mean(axis=0) - camera.centre)) - 0.6
    half_width_px = 0.5 * FIGURE_WIDTH * camera.K[0, 0] / distance
    u_centre = u_high - FIGURE_OVERLAP * (u_high - u_low) + half_width_px
    ray = camera.rays(np.array([[u_centre, camera.K[1, 2]]]))
    spot = ray_plane_intersection(camera.centre, ray, normal, distance)[0] * [1.0, 1.0, 0.0]
    right = camera.rotation[:, 0]
    half = 0.5 * FIGURE_WIDTH * right
    top = [0.0, 0.0, 0.8 * FIGURE_HEIGHT]
    mask = np.zeros((camera.height, camera.width), dtype=np.uint8)
    body, depth = camera.project(np.array([spot - half, spot + half, spot + half + top, spot - half + top]))
    if np.all(depth > 0):
        cv2.fillPoly(mask, [np.round(body).astype(np.int32)], 1)
        head = spot + [0.0, 0.0, 0.9 * FIGURE_HEIGHT]
        centre_and_edge, _ = camera.project(np.array([head, head + 0.1 * right]))
        radius = int(round(np.linalg.norm(centre_and_edge[1] - centre_and_edge[0])))
        cv2.circle(mask, (int(round(centre_and_edge[0, 0])), int(round(centre_and_edge[0, 1]))), radius, 1, -1)
    return mask.astype(bool)
