"""The demonstration: a tool seen as a line segment, head and handle-end points over time.

This is stage (i)'s output and the input of everything after it. Frames: world, metres, z up, the
ground at z = 0. Roll about the tool axis is unknown in a demonstration; alignment samples it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from toolimit.errors import DemoError

#: Fewer frames than this cannot hold a tool motion worth aligning (a fraction of a second).
MIN_FRAMES = 10
#: A tool shorter than this (head to handle end, metres) is taken as a broken reconstruction.
MIN_TOOL_LENGTH = 0.05
#: The frame rates (Hz) a video of a demonstration can have: from a 1 fps time-lapse to a 1000 fps
#: high-speed camera. Outside them a file's fps is an error, not a motion: 30 frames at 1e-6 fps
#: would be a year-long motion that alignment resamples at the scene's 24 fps (23.7 GB).
MIN_FPS, MAX_FPS = 1.0, 1000.0
#: The longest demonstration (s): one tool motion filmed in one take lasts seconds; ten minutes.
MAX_DURATION_S = 600.0
#: The most frames of a demonstration: ten minutes at 166 fps, or 100 s at 1000 fps.
MAX_FRAMES = 100_000


def frame_rate_problem(fps: object) -> str | None:
    """Why ``fps`` cannot be a demonstration's frame rate (Hz), or None when it can."""
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)) or not np.isfinite(fps):
        return f"must be a number of frames per second, got {fps!r}"
    if not MIN_FPS <= fps <= MAX_FPS:
        return f"must be between {MIN_FPS:g} and {MAX_FPS:g} frames per second (a video's), got {fps:g}"
    return None


@dataclass(frozen=True, eq=False)
class ToolDemo:
    """Head and handle-end trajectories of a tool.

    Attributes:
        head: (T, 3) tool head (working end: spade blade tip, hammer head, scythe blade) in the
            world frame, metres.
        handle: (T, 3) handle end (where a robot flange holds the tool), world frame, metres.
        fps: frames per second of the samples.
        tool: tool name ("spade", "hammer", "scythe", ...).
        source: free text saying where the demonstration came from (file, generator and seed).
    """

    head: np.ndarray
    handle: np.ndarray
    fps: float
    tool: str
    source: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        head = np.array(self.head, dtype=float)
        handle = np.array(self.handle, dtype=float)
        for name, points in (("head", head), ("handle", handle)):
            if points.ndim != 2 or points.shape[1] != 3:
                raise DemoError(f"{name}: expected shape (T, 3), got {points.shape}")
            if not np.all(np.isfinite(points)):
                bad = np.unique(np.nonzero(~np.isfinite(points))[0])
                raise DemoError(f"{name}: non-finite values (NaN or inf) at frames {bad[:10].tolist()}")
        if head.shape != handle.shape:
            raise DemoError(f"head {head.shape} and handle {handle.shape} have different shapes")
        if head.shape[0] < MIN_FRAMES:
            raise DemoError(f"too few frames: {head.shape[0]} (need at least {MIN_FRAMES})")
        if head.shape[0] > MAX_FRAMES:
            raise DemoError(f"too many frames: {head.shape[0]} (at most {MAX_FRAMES})")
        if problem := frame_rate_problem(self.fps):
            raise DemoError(f"fps: {problem}")
        duration = (head.shape[0] - 1) / float(self.fps)
        if duration > MAX_DURATION_S:
            raise DemoError(
                f"duration {duration:g} s ({head.shape[0]} frames at {self.fps:g} fps) is above {MAX_DURATION_S:g} s"
            )
        if not isinstance(self.tool, str) or not self.tool:
            raise DemoError(f"tool: must be a non-empty name, got {self.tool!r}")
        lengths = np.linalg.norm(handle - head, axis=1)
        if np.min(lengths) < MIN_TOOL_LENGTH:
            frame = int(np.argmin(lengths))
            raise DemoError(
                f"tool length {lengths[frame]:.4f} m at frame {frame} is below {MIN_TOOL_LENGTH} m "
                "(head and handle coincide)"
            )
        head.setflags(write=False)
        handle.setflags(write=False)
        object.__setattr__(self, "head", head)
        object.__setattr__(self, "handle", handle)
        object.__setattr__(self, "fps", float(self.fps))

    def __eq__(self, other: object) -> bool:
        """Same tool, fps and identical head and handle arrays (``source`` is not compared)."""
        if not isinstance(other, ToolDemo):
            return NotImplemented
        return (
            self.tool == other.tool
            and self.fps == other.fps
            and np.array_equal(self.head, other.head)
            and np.array_equal(self.handle, other.handle)
        )

    __hash__ = None  # type: ignore[assignment]  # equality is by array value, so demos are not hashable

    # --- derived quantities -------------------------------------------------------------------
    @property
    def n_frames(self) -> int:
        return self.head.shape[0]

    @property
    def dt(self) -> float:
        """Time between frames, seconds."""
        return 1.0 / self.fps

    @property
    def duration(self) -> float:
        """Time from the first to the last frame, seconds."""
        return (self.n_frames - 1) / self.fps

    @property
    def times(self) -> np.ndarray:
        """(T,) time of each frame, seconds from the first."""
        return np.arange(self.n_frames) / self.fps

    @property
    def axis(self) -> np.ndarray:
        """(T, 3) unit vector from head to handle end (the tool axis), world frame."""
        d = self.handle - self.head
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    @property
    def lengths(self) -> np.ndarray:
        """(T,) head-to-handle distance per frame, metres."""
        return np.linalg.norm(self.handle - self.head, axis=1)

    @property
    def length(self) -> float:
        """Median tool length, metres."""
        return float(np.median(self.lengths))

    def head_velocity(self) -> np.ndarray:
        """(T, 3) head velocity, m/s, central differences (one-sided at the ends)."""
        return np.gradient(self.head, self.dt, axis=0)

    def speed(self) -> np.ndarray:
        """(T,) tool speed, m/s: the mean speed of head and handle end.

        The paper's keypoints use the tool speed; averaging both ends keeps a pure rotation about
        the head (a hammer wrist flick) visible.
        """
        v_head = np.linalg.norm(np.gradient(self.head, self.dt, axis=0), axis=1)
        v_handle = np.linalg.norm(np.gradient(self.handle, self.dt, axis=0), axis=1)
        return 0.5 * (v_head + v_handle)

    # --- transforms (each returns a new demo) --------------------------------------------------
    def translated(self, offset: np.ndarray) -> ToolDemo:
        """Shift both paths by ``offset`` (3,), metres."""
        offset = np.asarray(offset, dtype=float).reshape(3)
        return replace(self, head=self.head + offset, handle=self.handle + offset)

    def scaled(self, factor: float, about: np.ndarray | None = None) -> ToolDemo:
        """Scale the *motion* about ``about`` (default: the first head point) by ``factor``.

        The tool keeps its length: the head path is scaled and the handle follows along the
        original tool axis, as the paper's trajectory scale does.
        """
        if not factor > 0:
            raise DemoError(f"scale factor must be positive, got {factor}")
        centre = self.head[0] if about is None else np.asarray(about, dtype=float).reshape(3)
        head = centre + factor * (self.head - centre)
        return replace(self, head=head, handle=head + self.axis * self.lengths[:, None])

    def rotated_yaw(self, angle: float, about: np.ndarray | None = None) -> ToolDemo:
        """Rotate both paths by ``angle`` (rad) about the vertical through ``about`` (default origin)."""
        c, s = np.cos(angle), np.sin(angle)
        rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        centre = np.zeros(3) if about is None else np.asarray(about, dtype=float).reshape(3)
        return replace(
            self,
            head=(self.head - centre) @ rz.T + centre,
            handle=(self.handle - centre) @ rz.T + centre,
        )

    def sliced(self, start: int = 0, stop: int | None = None) -> ToolDemo:
        """Frames ``start`` to ``stop`` (Python slice semantics)."""
        return replace(self, head=self.head[start:stop], handle=self.handle[start:stop])

    def resampled(self, fps: float) -> ToolDemo:
        """The same motion at another frame rate (linear interpolation of both points)."""
        if problem := frame_rate_problem(fps):
            raise DemoError(f"fps: {problem}")
        n = int(np.floor(self.duration * fps + 1e-9)) + 1
        t_new = np.arange(n) / fps
        interp = lambda x: np.stack([np.interp(t_new, self.times, x[:, k]) for k in range(3)], 1)  # noqa: E731
        return replace(self, head=interp(self.head), handle=interp(self.handle), fps=fps)

    def projected_to_plane(self, plane: str) -> ToolDemo:
        """The demo flattened onto a world plane for the planar scenes.

        ``plane="xz"`` (vertical plane: spade, hammer): the paths are first turned about z so that
        the main horizontal motion of the head lies along x (principal direction), then y := 0.
        ``plane="xy"`` (horizontal plane: scythe): z := 0 is *not* applied, because the scythe's
        cut depends on blade height; the plane is only the one the motion sweeps.
        """
        if plane == "xy":
            return self
        if plane != "xz":
            raise DemoError(f"plane: expected 'xz' or 'xy', got {plane!r}")
        horizontal = self.head[:, :2] - self.head[:, :2].mean(axis=0)
        _, _, vt = np.linalg.svd(horizontal, full_matrices=False)
        direction = vt[0]
        # Keep the sign so that the motion goes on average towards +x.
        if np.dot(self.head[-1, :2] - self.head[0, :2], direction) < 0:
            direction = -direction
        flat = self.rotated_yaw(-np.arctan2(direction[1], direction[0]))
        head, handle = flat.head.copy(), flat.handle.copy()
        head[:, 1] = 0.0
        handle[:, 1] = 0.0
        # Dropping y shortens a tool that points across the plane: keep each frame's length.
        axis = handle - head
        norm = np.linalg.norm(axis, axis=1, keepdims=True)
        axis = np.where(norm > 1e-9, axis / np.maximum(norm, 1e-12), np.array([0.0, 0.0, 1.0]))
        return replace(self, head=head, handle=head + axis * self.lengths[:, None])


def finite_frames(path: Path, key: str, value: np.ndarray, frame_axis: int) -> np.ndarray:
    """``value`` (2-D, frames along ``frame_axis``) as floats; DemoError naming the file and the key
    if it is not numeric, or the first frames that hold NaN or inf. The check every demonstration
    reader (:mod:`.npz_format`, :mod:`.motion_estimator`) runs on an array it read."""
    if not np.issubdtype(value.dtype, np.number):
        raise DemoError(f"{path}: key {key!r} must be numeric, got dtype {value.dtype}")
    value = value.astype(float)
    if not np.all(np.isfinite(value)):
        frames = np.unique(np.nonzero(~np.isfinite(value))[frame_axis])
        raise DemoError(f"{path}: key {key!r} has NaN or inf at frames {frames[:10].tolist()}")
    return value
