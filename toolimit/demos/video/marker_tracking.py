"""Colour-marker tracking: the centres of the red (head) and blue (handle end) discs in each frame of
a video, as endpoint tracks. Needs OpenCV (the ``[video]`` extra).

Measured on a rendered MP4 (``benchmarks/video_lift.py``): well under a pixel from the true
projection. OpenCV's generic object trackers were unreliable on these videos and mediapipe's
current wheels ship no models, so the package tracks markers; a real video's tracks come from any
outside detector or labelling tool, as a tracks CSV (:mod:`.tracks`).
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

from toolimit.demos.video.render import HANDLE_MARKER, HEAD_MARKER, Marker
from toolimit.demos.video.tracks import EndpointTracks
from toolimit.errors import TrackError

#: A marker counts as seen when at least this share of its disc's area shows.
MIN_VISIBLE_AREA = 0.5
#: Least saturation and brightness (0-255) of a marker pixel: the scene's other colours are duller.
MIN_SATURATION, MIN_VALUE = 120, 90


def track_markers(
    path: str | os.PathLike[str], markers: tuple[Marker, Marker] = (HEAD_MARKER, HANDLE_MARKER)
) -> EndpointTracks:
    """The tracks of the head and handle-end ``markers`` in the video at ``path``: each end's
    centre is the centroid of the largest blob of its colour, and the end is not visible in a
    frame where that blob covers less than ``MIN_VISIBLE_AREA`` of the disc."""
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        raise TrackError(f"{path}: OpenCV cannot read this video")
    centres: list[list[np.ndarray]] = [[], []]
    try:
        while True:
            ok, image = capture.read()
            if not ok:
                break
            hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
            for found, marker in zip(centres, markers):
                found.append(_centre(hsv, marker))
    finally:
        capture.release()
    if not centres[0]:
        raise TrackError(f"{Path(path)}: the video has no frames")
    head, handle = (np.array(found) for found in centres)
    return EndpointTracks(head, handle, np.all(np.isfinite(head), axis=1), np.all(np.isfinite(handle), axis=1))


def _centre(hsv: np.ndarray, marker: Marker) -> np.ndarray:
    """(2,) the marker's centre (u, v) pixels in one HSV image, or NaN when it is not seen."""
    hue, saturation, value = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    low, high = marker.hue
    in_hue = (hue >= low) | (hue <= high) if low > high else (hue >= low) & (hue <= high)
    mask = (in_hue & (saturation >= MIN_SATURATION) & (value >= MIN_VALUE)).astype(np.uint8)
    count, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
    if count < 2:
        return np.full(2, np.nan)
    largest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    if stats[largest, cv2.CC_STAT_AREA] < MIN_VISIBLE_AREA * np.pi * marker.radius**2:
        return np.full(2, np.nan)
    return centroids[largest]
