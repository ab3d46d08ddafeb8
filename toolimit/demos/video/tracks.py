"""2D endpoint tracks: where the tool's head and handle end are in each image, and whether they are seen.

The tracks file is a CSV another tool (a labelling tool, a keypoint detector) can write, with the
header ``frame,head_u,head_v,handle_u,handle_v,head_visible,handle_visible``: one row per frame,
frames 0, 1, 2, ... in order, pixels with their origin at the image's top-left corner (u right,
v down), visibility 0 or 1. The pixels of an end that is not visible are ignored and may be empty.
"""

from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from toolimit.artifacts import save_text
from toolimit.demos.tool_demo import ToolDemo
from toolimit.demos.video.camera import Camera
from toolimit.errors import TrackError

#: The tracks file's header, in this order.
TRACKS_HEADER = ("frame", "head_u", "head_v", "handle_u", "handle_v", "head_visible", "handle_visible")


@dataclass(frozen=True, eq=False)
class EndpointTracks:
    """The image positions of the tool's two ends over a video.

    Attributes:
        head, handle: (T, 2) pixels (u right, v down, origin top-left) of the head and the handle
            end; NaN where that end is not visible.
        head_visible, handle_visible: (T,) bool, whether each end is seen in each frame.
    """

    head: np.ndarray
    handle: np.ndarray
    head_visible: np.ndarray
    handle_visible: np.ndarray

    def __post_init__(self) -> None:
        arrays = {
            name: np.asarray(getattr(self, name)) for name in ("head", "handle", "head_visible", "handle_visible")
        }
        frames = len(arrays["head"])
        for name in ("head", "handle"):
            if arrays[name].shape != (frames, 2):
                raise TrackError(f"tracks {name}: expected shape ({frames}, 2), got {arrays[name].shape}")
            seen = arrays[f"{name}_visible"]
            if seen.shape != (frames,):
                raise TrackError(f"tracks {name}_visible: expected shape ({frames},), got {seen.shape}")
            seen = seen.astype(bool)
            points = arrays[name].astype(float).copy()
            bad = seen & ~np.all(np.isfinite(points), axis=1)
            if np.any(bad):
                raise TrackError(f"tracks {name}: visible but not finite at frames {np.flatnonzero(bad)[:10].tolist()}")
            points[~seen] = np.nan
            points.setflags(write=False)
            seen.setflags(write=False)
            object.__setattr__(self, name, points)
            object.__setattr__(self, f"{name}_visible", seen)

    @property
    def n_frames(self) -> int:
        return len(self.head)


def project_demo(demo: ToolDemo, camera: Camera) -> EndpointTracks:
    """The exact tracks of ``demo`` seen by ``camera``: an end is visible when it projects inside
    the image, in front of the camera (no occlusion: see :mod:`.render` for that)."""
    ends = {}
    for name, points in (("head", demo.head), ("handle", demo.handle)):
        pixels, depth = camera.project(points)
        ends[name] = pixels
        ends[f"{name}_visible"] = camera.inside(pixels, depth)
    return EndpointTracks(**ends)


def perturbed(tracks: EndpointTracks, noise_px: float, drop_fraction: float, seed: int) -> EndpointTracks:
    """``tracks`` as a tracker would give them: Gaussian pixel noise of ``noise_px`` standard
    deviation on both coordinates of both ends, and ``drop_fraction`` of the frames (drawn at
    random) where neither end was found. Same seed, same tracks."""
    rng = np.random.default_rng(seed)
    dropped = np.zeros(tracks.n_frames, dtype=bool)
    dropped[rng.permutation(tracks.n_frames)[: int(round(drop_fraction * tracks.n_frames))]] = True
    noise = rng.normal(scale=noise_px, size=(2, tracks.n_frames, 2))
    return replace(
        tracks,
        head=tracks.head + noise[0],
        handle=tracks.handle + noise[1],
        head_visible=tracks.head_visible & ~dropped,
        handle_visible=tracks.handle_visible & ~dropped,
    )


def tracks_csv(tracks: EndpointTracks) -> str:
    """The tracks file's text (pixels to 1/1000 px; an unseen end's pixels empty)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(TRACKS_HEADER)
    for frame in range(tracks.n_frames):
        row: list[object] = [frame]
        for name in ("head", "handle"):
            seen = tracks.head_visible[frame] if name == "head" else tracks.handle_visible[frame]
            point = getattr(tracks, name)[frame]
            row += [f"{point[0]:.3f}", f"{point[1]:.3f}"] if seen else ["", ""]
        row += [int(tracks.head_visible[frame]), int(tracks.handle_visible[frame])]
        writer.writerow(row)
    return buffer.getvalue()


def write_tracks(tracks: EndpointTracks, path: str | os.PathLike[str]) -> None:
    """Write the tracks file atomically."""
    save_text(path, tracks_csv(tracks))


def read_tracks(path: str | os.PathLike[str]) -> EndpointTracks:
    """The tracks file at ``path``; TrackError naming the file, the line and the field that is wrong."""
    path = Path(path)
    with open(path, encoding="utf-8", newline="") as stream:
        rows = list(csv.reader(stream))
    if not rows or tuple(cell.strip() for cell in rows[0]) != TRACKS_HEADER:
        found = ",".join(rows[0]) if rows else "an empty file"
        raise TrackError(f"{path}: line 1: expected the header {','.join(TRACKS_HEADER)}, got {found}")
    points = np.full((len(rows) - 1, 4), np.nan)
    seen = np.zeros((len(rows) - 1, 2), dtype=bool)
    for index, row in enumerate(rows[1:]):
        line = index + 2
        if len(row) != len(TRACKS_HEADER):
            raise TrackError(f"{path}: line {line}: expected {len(TRACKS_HEADER)} fields, got {len(row)}")
        cells = dict(zip(TRACKS_HEADER, (cell.strip() for cell in row)))
        if cells["frame"] != str(index):
            raise TrackError(
                f"{path}: line {line}: frame: expected {index} (frames 0, 1, 2, ... in order), got {cells['frame']!r}"
            )
        for column, name in enumerate(("head_visible", "handle_visible")):
            if cells[name] not in ("0", "1"):
                raise TrackError(f"{path}: line {line}: {name}: expected 0 or 1, got {cells[name]!r}")
            seen[index, column] = cells[name] == "1"
        for column, name in enumerate(("head_u", "head_v", "handle_u", "handle_v")):
            if not seen[index, column // 2]:
                continue
            try:
                points[index, column] = float(cells[name])
            except ValueError:
                raise TrackError(
                    f"{path}: line {line}: {name}: expected a number of pixels, got {cells[name]!r}"
                ) from None
            if not np.isfinite(points[index, column]):
                raise TrackError(
                    f"{path}: line {line}: {name}: expected a finite number of pixels, got {cells[name]!r}"
                )
    if not len(points):
        raise TrackError(f"{path}: no frames after the header")
    return EndpointTracks(points[:, :2], points[:, 2:], seen[:, 0], seen[:, 1])
