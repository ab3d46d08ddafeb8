"""The lift: 2D endpoint tracks and a calibrated camera become a 3D demonstration.

One view cannot give depth, so the lift uses what the scene tells (measured: a full 3D lift by
reprojection error, tool length and smoothness alone was ill-posed here, 0.65-3 m off):

1. **The working plane.** The head moves in a vertical plane facing the camera (its normal is the
   camera's viewing direction made horizontal), or turned as the user says (``plane_normal``: one
   view cannot tell how the motion is turned). Its distance comes from the frames where the head
   touches the ground: a head ray that points below the horizon meets the ground z = 0 at a
   horizontal distance ``d``; a head on or above the ground lies no farther than that, so the
   plane is as far as the nearest such meetings (the mean of the lowest ``contact_share`` of them).
   Or it is given: a known point of the plane (the hammer's nail). Or the user says the whole tool
   moves in a plane (``fit_plane_normal``): every point of a tool in planar motion keeps its
   distance from the head's plane, so the plane's turn is the one of ``PLANE_TURNS`` under which
   the lifted handle end's distance from the head's plane varies least (:func:`fit_plane_turn`).
   Where no tool of the given length joins the lifted head to the handle's rays in many frames,
   the plane is wrong and the lift refuses.
2. **The head** is its ray's intersection with that plane (closed form).
3. **The handle end** lies on its own ray at the tool's length from the head: two solutions, the
   near one (nearer to the camera than the foot of the head on that ray) and the far one, at a signed
   depth offset ``s = -o`` or ``+o`` from that foot. The mirror image of a motion seen from one view
   is as plausible as the motion, so the side is the user's knowledge (``handle_hint``), and a frame
   leaves the hinted side only on evidence from the image (:func:`choose_sides`): the depth offset
   crosses zero (the tool turns through the plane square to the handle's ray) and the frames around
   fit a crossing better than a bounce by ``SWITCH_EVIDENCE`` squared standard deviations. Nothing
   in one view tells the side of a whole stretch: the smoother of a 3D path and its mirror image
   can be the mirror image, and a handle end under the ground rules nothing out (the authors'
   recordings put it 14 cm under). Without a hint the lift refuses rather than return a mirrored
   demonstration, unless the two solutions are negligibly apart. Each frame records where its side
   came from, the evidence, and how far the mirror solution is.
4. **The handle's depth** along its ray is smoothed over time: its signed offset from the foot
   (+ far, - near) is filtered by a Gaussian in time. Where the ray grazes the sphere of the tool's length
   (a tool seen nearly side-on), the offset is the square root of a small noisy number: pixel noise
   there becomes a one-sided depth error, and the near/far choice flips between frames; filtering
   the signed offset averages the flips out, which filtering the pixels alone cannot do.

Before all this, each end's pixel track is filtered by a Gaussian in time whose width is chosen for
that end by generalised cross-validation (:func:`cross_validated_width`): as narrow as a fast turn
needs, as wide as a slow motion's noise allows. Frames where an end is not visible are filled by
linear interpolation of the lifted points. The
per-frame uncertainty is the position change caused by the track error left after smoothing
(``pixel_noise`` pixels before it) and by the plane distance's uncertainty: it does not include the
motion's departure from the plane, which is the main error on real motions
(docs/results/video_lift.md#video-lift).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from toolimit.demos.tool_demo import MIN_FRAMES, ToolDemo
from toolimit.demos.video.camera import Camera
from toolimit.demos.video.tracks import EndpointTracks
from toolimit.errors import InvalidSetting, TrackError

#: ``handle_hint`` values: the handle end nearer to / farther from the camera than the head.
HANDLE_HINTS = ("near", "far")
#: A zero crossing of the handle's depth offset moves frames off the hinted side when a bounce fits
#: the frames around it worse than a crossing by this many squared standard deviations (5 sigma).
SWITCH_EVIDENCE = 25.0
#: Frames each side of a graze fitted to tell a crossing from a bounce.
CROSSING_WINDOW = 6
#: The least standard uncertainty (metres) of a depth offset in the crossing test, whatever the
#: pixel noise: the head leaving its plane moves the lifted offsets by centimetres, enough to make a
#: tangent touch on exact tracks look like a crossing.
OFFSET_SIGMA_FLOOR = 0.01
#: Separations of the two solutions below this (metres) change nothing that matters.
NEGLIGIBLE_OFFSET = 0.005
#: A handle ray passing farther than the tool's length plus this (metres) from the lifted head
#: misses the tool: in more than ``MAX_MISSED_SHARE`` of the frames, the working plane is wrong.
MISS_MARGIN, MAX_MISSED_SHARE = 0.05, 0.2
#: Where each frame's side comes from (``LiftedDemo.side_source``).
SIDE_SOURCES = ("hint", "crossing", "negligible")
#: The plane turns (degrees from facing the camera) ``fit_plane_normal`` chooses from: a plane seen
#: nearer edge-on than ``MAX_PLANE_ANGLE`` is refused anyway, and a best turn at either end of the
#: range is no minimum.
PLANE_TURNS = tuple(range(-70, 71, 5))
#: The pixel filter widths (frames, Gaussian standard deviation) cross-validation chooses from:
#: 0.5 to 8 frames in steps of sqrt(2).
PIXEL_WIDTHS = tuple(0.5 * 2 ** (k / 2) for k in range(9))


@dataclass(frozen=True)
class LiftSettings:
    """How tracks are lifted to 3D (``toolimit demo lift``).

    Attributes:
        handle_hint: the side of the head the handle end is on, the user's knowledge: "near"
            (nearer to the camera than the head) or "far"; each frame keeps it unless the image
            shows otherwise. None: the image alone decides, or the lift refuses.
        tool_length: head to handle end, metres (None: the tool's registered length).
        plane_point: a world point (x, y, z metres) on the head's working plane (None: the plane
            from the frames where the head touches the ground).
        plane_normal: the working plane's horizontal normal (x, y, world; its length and sign do
            not matter): how the motion is turned, which one view cannot tell and the user knows,
            say from a calibration board laid along the motion (None: the camera's viewing
            direction made horizontal, a camera facing the motion).
        fit_plane_normal: the whole tool moves in a plane (not just its head): the plane's normal
            is fitted from the tracks (:func:`fit_plane_turn`) instead of facing the camera; not
            with ``plane_normal``.
        contact_share: share of the head's frames taken as its ground contacts (the nearest
            ray-ground meetings).
        pixel_noise: standard deviation of the tracks' pixel error, for the per-frame uncertainty.
        smoothing: standard deviation, in frames, of the Gaussian filter run along each end's pixel
            track before the lift (0: none; None: chosen for each end by generalised
            cross-validation from ``PIXEL_WIDTHS``); it averages out track noise a tool's motion at
            video rates does not have.
        offset_smoothing: standard deviation, in frames, of the Gaussian filter run along the
            handle end's signed depth offset after the near/far choice (0: none).
        min_visible_share: each end must be visible in at least this share of the frames.
    """

    handle_hint: str | None = None
    tool_length: float | None = None
    plane_point: tuple[float, float, float] | None = None
    plane_normal: tuple[float, float] | None = None
    fit_plane_normal: bool = False
    contact_share: float = 0.05
    pixel_noise: float = 3.0
    smoothing: float | None = None
    offset_smoothing: float = 1.0
    min_visible_share: float = 0.5

    def __post_init__(self) -> None:
        if self.handle_hint is not None and self.handle_hint not in HANDLE_HINTS:
            raise InvalidSetting("handle_hint", f"expected near or far, got {self.handle_hint!r}")
        if self.tool_length is not None and not (math.isfinite(self.tool_length) and self.tool_length > 0):
            raise InvalidSetting("tool_length", f"must be a positive number of metres, got {self.tool_length!r}")
        if self.plane_point is not None and (
            len(self.plane_point) != 3 or not all(math.isfinite(value) for value in self.plane_point)
        ):
            raise InvalidSetting("plane_point", f"expected three finite coordinates x, y, z, got {self.plane_point!r}")
        if self.plane_normal is not None and (
            len(self.plane_normal) != 2
            or not all(math.isfinite(value) for value in self.plane_normal)
            or math.hypot(*self.plane_normal) == 0
        ):
            raise InvalidSetting(
                "plane_normal", f"expected two finite coordinates x, y, not both 0, got {self.plane_normal!r}"
            )
        if self.fit_plane_normal and self.plane_normal is not None:
            raise InvalidSetting("fit_plane_normal", "give either plane_normal or fit_plane_normal, not both")
        if not 0 < self.contact_share <= 1:
            raise InvalidSetting("contact_share", f"must be in (0, 1], got {self.contact_share!r}")
        if not (math.isfinite(self.pixel_noise) and self.pixel_noise >= 0):
            raise InvalidSetting("pixel_noise", f"must be a non-negative number of pixels, got {self.pixel_noise!r}")
        if self.smoothing is not None and not (math.isfinite(self.smoothing) and self.smoothing >= 0):
            raise InvalidSetting(
                "smoothing", f"must be a non-negative number of frames or None, got {self.smoothing!r}"
            )
        if not (math.isfinite(self.offset_smoothing) and self.offset_smoothing >= 0):
            raise InvalidSetting(
                "offset_smoothing", f"must be a non-negative number of frames, got {self.offset_smoothing!r}"
            )
        if not 0 < self.min_visible_share <= 1:
            raise InvalidSetting("min_visible_share", f"must be in (0, 1], got {self.min_visible_share!r}")


@dataclass(frozen=True, eq=False)
class LiftedDemo:
    """A lift's result.

    Attributes:
        demo: the demonstration (world frame, metres).
        head_sigma, handle_sigma: (T,) each end's standard position uncertainty, metres, from the
            track noise and the plane's distance (not from the motion leaving the plane).
        head_filled, handle_filled: (T,) bool, frames where that end was not visible and was
            interpolated.
        handle_far: (T,) bool, whether the far solution was taken for the handle end.
        side_source: (T,) str, what set each frame's side (``SIDE_SOURCES``): "hint" (the image shows
            nothing against the hint), "crossing" (a zero crossing of the depth offset moved it off
            the hint), "negligible"
            (the two solutions are within ``NEGLIGIBLE_OFFSET`` all along its stretch).
        side_margin: (T,) the image's evidence for a frame off the hinted side: the weakest zero
            crossing's (:func:`choose_sides`), squared standard deviations; 0 where the hint holds.
        mirror_distance: (T,) metres between the handle end and its mirror solution (twice the
            depth offset): the error of a frame on the wrong side.
        plane_normal: (3,) horizontal unit normal of the working plane, pointing away from the camera.
        plane_turn: the plane's normal's turn from the camera's viewing direction made horizontal,
            degrees (counter-clockwise seen from above).
        plane_distance: the plane's distance from the camera's centre along that normal, metres.
        hint_used: whether any frame's side came from ``handle_hint`` alone.
        pixel_smoothing: the pixel filter's width for the head and for the handle end, frames.
    """

    demo: ToolDemo
    head_sigma: np.ndarray
    handle_sigma: np.ndarray
    head_filled: np.ndarray
    handle_filled: np.ndarray
    handle_far: np.ndarray
    side_source: np.ndarray
    side_margin: np.ndarray
    mirror_distance: np.ndarray
    plane_normal: np.ndarray
    plane_distance: float
    plane_turn: float
    hint_used: bool
    pixel_smoothing: tuple[float, float]


def ray_plane_intersection(origin: np.ndarray, rays: np.ndarray, normal: np.ndarray, distance: float) -> np.ndarray:
    """(N, 3) points where the rays ``origin + s * rays`` (origin (3,), rays (N, 3)) meet the plane
    ``normal @ (p - origin) = distance``; NaN for a ray parallel to it or meeting it behind."""
    along = rays @ normal
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(along > 1e-12, distance / along, np.nan)
    return origin + rays * scale[:, None]


def squared_offset(
    origin: np.ndarray, rays: np.ndarray, head: np.ndarray, length: float
) -> tuple[np.ndarray, np.ndarray]:
    """The foot of ``head`` (N, 3) on the unit rays ``origin + s * rays`` (its ``s``, metres) and the
    squared distance (N,) m^2 from that foot to the ray's points at ``length`` metres from the head:
    ``length^2`` minus the ray's squared distance from the head, negative where the ray misses."""
    relative = head - origin
    foot = np.sum(rays * relative, axis=1)
    return foot, foot**2 - np.sum(relative**2, axis=1) + length**2


def handle_candidates(
    origin: np.ndarray, rays: np.ndarray, head: np.ndarray, length: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The near and far points (N, 3 each) on the rays ``origin + s * rays`` at ``length`` metres
    from ``head`` (N, 3), and their half-separation (N,) metres. A ray that passes farther than
    ``length`` from the head gives its closest point for both."""
    foot, squared = squared_offset(origin, rays, head, length)
    offset = np.sqrt(np.maximum(squared, 0.0))
    return _on_ray(origin, rays, foot - offset), _on_ray(origin, rays, foot + offset), offset


def _on_ray(origin: np.ndarray, rays: np.ndarray, along: np.ndarray) -> np.ndarray:
    """(N, 3) the points ``along`` (N,) metres on the rays, none behind the camera."""
    return origin + rays * np.maximum(along, 0.0)[:, None]


def handle_side(demo: ToolDemo, camera: Camera) -> str:
    """The hint that is right for most frames of a known ``demo`` seen by ``camera``: "far" when its
    handle end lies beyond the foot of the head on the handle's ray in most frames, else "near"
    (for benchmarks and notebooks that lift a motion whose truth they have)."""
    rays = camera.rays(camera.project(demo.handle)[0])
    beyond = np.sum(rays * (demo.handle - camera.centre), axis=1) > np.sum(rays * (demo.head - camera.centre), axis=1)
    return "far" if np.mean(beyond) > 0.5 else "near"


def lift_tracks(tracks: EndpointTracks, camera: Camera, tool: str, fps: float, settings: LiftSettings) -> LiftedDemo:
    """The 3D demonstration of ``tracks`` seen by ``camera`` (see the module docstring).

    Raises:
        TrackError: too few visible frames, a camera not above the ground or looking straight
            down, a camera that sees no ground, a plane seen nearly edge-on or that no tool of the
            given length fits, a mirror ambiguity without a hint, no fitted plane turn.
    """
    if settings.fit_plane_normal:
        return fit_plane_turn(tracks, camera, tool, fps, settings)
    from toolimit.tools import tool_spec

    length = settings.tool_length if settings.tool_length is not None else tool_spec(tool).length
    _check_visible(tracks, settings.min_visible_share)
    widths = pixel_widths(tracks, settings.smoothing)
    tracks = smoothed(tracks, widths)
    origin = camera.centre
    if origin[2] <= 0:
        raise TrackError(f"camera: its centre is at height {origin[2]:.3f} m, not above the ground (z = 0)")
    forward = camera.rotation[:, 2]
    if np.linalg.norm(forward[:2]) < 1e-3:
        raise TrackError("camera: it looks straight up or down; the lift needs a camera facing the working plane")
    normal = _plane_normal(forward, settings.plane_normal)
    facing = _plane_normal(forward, None)

    head_frames = np.flatnonzero(tracks.head_visible)
    head_rays = camera.rays(tracks.head[head_frames])
    behind = head_frames[head_rays @ normal <= 1e-6]
    if behind.size:
        raise TrackError(f"tracks: the head's ray points away from the working plane at frames {behind[:10].tolist()}")
    distance, distance_sigma = _plane_distance(camera, tracks.head[head_frames], normal, settings, widths[0])
    head = _filled(ray_plane_intersection(origin, head_rays, normal, distance), head_frames, tracks.n_frames)

    handle_frames = np.flatnonzero(tracks.handle_visible)
    handle_rays = camera.rays(tracks.handle[handle_frames])
    near, far, offset = handle_candidates(origin, handle_rays, head[handle_frames], length)
    _check_plane_fits(origin, handle_rays, head[handle_frames], length)
    head_moves = _head_moves(camera, tracks, head_frames, normal, distance, distance_sigma, settings, widths[0])
    offset_sigma = _handle_spreads(camera, tracks, handle_frames, head, head_moves, length, settings, widths[1])[2]
    sides = choose_sides(near, far, offset, offset_sigma, settings.handle_hint)
    signed = np.where(sides.far, offset, -offset)
    if settings.offset_smoothing > 0:
        signed = _filtered(signed[:, None], handle_frames, tracks.n_frames, settings.offset_smoothing)[handle_frames, 0]
    foot, _ = squared_offset(origin, handle_rays, head[handle_frames], length)
    handle = _filled(_on_ray(origin, handle_rays, foot + signed), handle_frames, tracks.n_frames)
    axis = handle - head
    handle = head + length * axis / np.linalg.norm(axis, axis=1, keepdims=True)

    head_sigma = np.sqrt(sum(np.sum((moved - head) ** 2, axis=1) for moved in head_moves))
    handle_sigma = _handle_sigma(camera, tracks, handle_frames, head, handle, head_moves, length, settings, widths[1])
    nearest = _nearest(handle_frames, tracks.n_frames)
    demo = ToolDemo(head, handle, fps, tool, source=f"lifted from 2D tracks ({tracks.n_frames} frames)")
    return LiftedDemo(
        demo=demo,
        head_sigma=head_sigma,
        handle_sigma=handle_sigma,
        head_filled=~tracks.head_visible,
        handle_filled=~tracks.handle_visible,
        handle_far=_filled(
            np.where(signed != 0, signed > 0, sides.far)[:, None].astype(float), handle_frames, tracks.n_frames
        )[:, 0]
        > 0.5,
        side_source=sides.source[nearest],
        side_margin=sides.margin[nearest],
        mirror_distance=_filled(2 * offset[:, None], handle_frames, tracks.n_frames)[:, 0],
        plane_normal=normal,
        plane_distance=distance,
        plane_turn=math.degrees(math.atan2(float(np.cross(facing, normal)[2]), float(facing @ normal))),
        hint_used=settings.handle_hint is not None and bool(np.any(sides.source == "hint")),
        pixel_smoothing=widths,
    )


def fit_plane_turn(tracks: EndpointTracks, camera: Camera, tool: str, fps: float, settings: LiftSettings) -> LiftedDemo:
    """The lift of ``tracks`` (:func:`lift_tracks`) through the working plane turned by the one of
    ``PLANE_TURNS`` (degrees from facing the camera) under which the lifted handle end's signed
    distance from the head's plane has the least standard deviation over the frames.

    Why: one view cannot tell how a vertical plane is turned, and the plane facing the camera puts
    a head that moves along a turned plane tens of centimetres off. A tool that moves in a plane
    (a rigid planar motion: each of its points moves parallel to the head's plane) keeps its handle
    end at one distance from the head's plane; through a wrongly turned plane the lifted handle end
    leaves it and returns as the tool turns. The head's path alone cannot tell: a plane's image is
    consistent with any turn.

    Raises:
        TrackError: every turn refused, or the best at either end of ``PLANE_TURNS`` (no minimum
            inside the range: the motion is not planar, or the plane is seen too near edge-on).
    """
    forward = camera.rotation[:, 2]
    if np.linalg.norm(forward[:2]) < 1e-3:
        raise TrackError("camera: it looks straight up or down; the lift needs a camera facing the working plane")
    facing = forward[:2] / np.linalg.norm(forward[:2])
    best: tuple[float, LiftedDemo] | None = None
    last_error: TrackError | None = None
    for turn in PLANE_TURNS:
        c, s = math.cos(math.radians(turn)), math.sin(math.radians(turn))
        normal = (float(c * facing[0] - s * facing[1]), float(s * facing[0] + c * facing[1]))
        try:
            lifted = lift_tracks(
                tracks, camera, tool, fps, replace(settings, fit_plane_normal=False, plane_normal=normal)
            )
        except TrackError as error:
            last_error = error
            continue
        spread = float(np.std((lifted.demo.handle - lifted.demo.head) @ lifted.plane_normal))
        if best is None or spread < best[0]:
            best = (spread, lifted)
    if best is None:
        raise TrackError(f"tracks: no plane turn from {PLANE_TURNS[0]} to {PLANE_TURNS[-1]} deg lifts: {last_error}")
    lifted = best[1]
    if round(lifted.plane_turn) in (PLANE_TURNS[0], PLANE_TURNS[-1]):
        raise TrackError(
            f"tracks: the fitted plane turn is at the end of its range ({lifted.plane_turn:.0f} deg from facing "
            "the camera): the tool's motion is not planar or its plane is seen nearly edge-on; give its plane's "
            "normal (--plane-normal x,y)"
        )
    return lifted


def _nearest(frames: np.ndarray, n_frames: int) -> np.ndarray:
    """(n_frames,) the index into ``frames`` (sorted) of the nearest one to each frame."""
    every = np.arange(n_frames)
    after = np.clip(np.searchsorted(frames, every), 0, len(frames) - 1)
    before = np.clip(after - 1, 0, len(frames) - 1)
    return np.where(np.abs(frames[before] - every) <= np.abs(frames[after] - every), before, after)


#: The working plane must face the camera within this angle (degrees) of its viewing direction.
MAX_PLANE_ANGLE = 75.0


def _plane_normal(forward: np.ndarray, given: tuple[float, float] | None) -> np.ndarray:
    """(3,) the working plane's horizontal unit normal, pointing away from the camera (viewing
    direction ``forward`` (3,), world): ``given`` (x, y) or the viewing direction made horizontal."""
    facing = np.array([forward[0], forward[1], 0.0]) / np.linalg.norm(forward[:2])
    if given is None:
        return facing
    normal = np.array([given[0], given[1], 0.0]) / math.hypot(*given)
    if normal @ facing < 0:
        normal = -normal
    angle = math.degrees(math.acos(min(1.0, float(normal @ facing))))
    if angle > MAX_PLANE_ANGLE:
        raise TrackError(
            f"plane_normal {given}: the working plane is seen {90 - angle:.0f} deg from edge-on (its normal "
            f"{angle:.0f} deg from the camera's viewing direction, at most {MAX_PLANE_ANGLE:g})"
        )
    return normal


def pixel_widths(tracks: EndpointTracks, smoothing: float | None) -> tuple[float, float]:
    """The pixel filter's width (frames) for the head and for the handle end: ``smoothing`` for
    both, or (None) each end's :func:`cross_validated_width`."""
    if smoothing is not None:
        return smoothing, smoothing
    head, handle = (
        cross_validated_width(getattr(tracks, name)[seen], seen, tracks.n_frames)
        for name, seen in (
            ("head", np.flatnonzero(tracks.head_visible)),
            ("handle", np.flatnonzero(tracks.handle_visible)),
        )
    )
    return head, handle


def cross_validated_width(values: np.ndarray, frames: np.ndarray, n_frames: int) -> float:
    """The width of ``PIXEL_WIDTHS`` (frames) whose time filter (:func:`_filtered`) gives ``values``
    (m, k), seen at ``frames`` (m,), the least generalised cross-validation score
    ``m * |values - S values|^2 / (m - trace S)^2``: an estimate of the error in predicting a
    left-out frame, which needs no noise level (Craven and Wahba, 1979). ``S`` is the filter's
    linear map from the seen values to their filtered values."""
    scores = []
    for width in PIXEL_WIDTHS:
        residual = values - _filtered(values, frames, n_frames, width)[frames]
        trace = float(np.sum(_filter_diagonal(frames, n_frames, width)))
        scores.append(len(frames) * float(np.sum(residual**2)) / (len(frames) - trace) ** 2)
    return PIXEL_WIDTHS[int(np.argmin(scores))]


def _filter_diagonal(frames: np.ndarray, n_frames: int, width: float) -> np.ndarray:
    """(m,) the diagonal of the time filter's linear map from values seen at ``frames`` (m,) to their
    filtered values: each value's weight on itself. A value reaches no farther than the filter's
    pad plus the longest gap, so impulses twice that far apart are filtered in one pass."""
    count = len(frames)
    longest_gap = int(np.max(np.diff(frames))) if count > 1 else 1
    spacing = 2 * (4 * math.ceil(width) + longest_gap) + 1
    diagonal = np.empty(count)
    for start in range(min(spacing, count)):
        chosen = np.arange(start, count, spacing)
        impulses = np.zeros((count, 1))
        impulses[chosen] = 1.0
        diagonal[chosen] = _filtered(impulses, frames, n_frames, width)[frames[chosen], 0]
    return diagonal


def smoothed(tracks: EndpointTracks, widths: tuple[float, float]) -> EndpointTracks:
    """``tracks`` with each end's pixels filtered along time by a Gaussian of ``widths`` (head,
    handle end) frames standard deviation (0: unfiltered; gaps bridged linearly for the filter;
    visibility unchanged)."""
    ends = {}
    for name, width in zip(("head", "handle"), widths):
        if width > 0:
            seen = np.flatnonzero(getattr(tracks, f"{name}_visible"))
            ends[name] = _filtered(getattr(tracks, name)[seen], seen, tracks.n_frames, width)
    return replace(tracks, **ends)


def _filtered(values: np.ndarray, frames: np.ndarray, n_frames: int, width: float) -> np.ndarray:
    """(n_frames, k) ``values`` (len(frames), k) known at ``frames``, gaps bridged linearly, then
    filtered along time by a Gaussian of ``width`` frames standard deviation. Each end is padded by
    its point reflection (``2 x[0] - x[k]``), so that a motion still moving at the first or last frame
    is not pulled towards the inside (as repeating the end frame would), at the price of more noise
    there."""
    from scipy.ndimage import gaussian_filter1d

    series = _filled(values, frames, n_frames)
    pad = min(4 * math.ceil(width), n_frames - 1)
    before = 2 * series[:1] - series[pad:0:-1]
    after = 2 * series[-1:] - series[-2 : -pad - 2 : -1]
    padded = np.concatenate([before, series, after])
    return gaussian_filter1d(padded, width, axis=0, mode="nearest")[pad : pad + n_frames]


def _check_plane_fits(origin: np.ndarray, rays: np.ndarray, heads: np.ndarray, length: float) -> None:
    """TrackError when the handle's rays (m, 3) pass farther than ``length + MISS_MARGIN`` metres
    from the lifted heads (m, 3) in more than ``MAX_MISSED_SHARE`` of the frames: no tool of that
    length joins them, so the working plane is not where the head moves."""
    _, squared = squared_offset(origin, rays, heads, length)
    missed = squared < length**2 - (length + MISS_MARGIN) ** 2
    if np.mean(missed) > MAX_MISSED_SHARE:
        raise TrackError(
            f"tracks: the working plane does not fit: in {int(np.sum(missed))} of {len(missed)} frames the handle "
            f"end's ray passes more than {MISS_MARGIN:g} m beyond the tool's length ({length:g} m) from the lifted "
            "head; if the motion is not square to the camera, give its plane's normal (--plane-normal x,y), or a "
            "point of it (--plane-point x,y,z)"
        )


def _check_visible(tracks: EndpointTracks, min_share: float) -> None:
    """TrackError unless each end is visible in enough frames to lift and interpolate."""
    needed = max(MIN_FRAMES, math.ceil(min_share * tracks.n_frames))
    for name, seen in (("head", tracks.head_visible), ("handle", tracks.handle_visible)):
        count = int(np.sum(seen))
        if count < needed:
            raise TrackError(
                f"tracks: too few visible frames: the {name} is seen in {count} of {tracks.n_frames} frames "
                f"(need at least {needed}: {min_share:.0%} of the frames and at least {MIN_FRAMES})"
            )


def _plane_distance(
    camera: Camera, pixels: np.ndarray, normal: np.ndarray, settings: LiftSettings, width: float
) -> tuple[float, float]:
    """The working plane's distance from the camera along ``normal`` (metres) and its standard
    uncertainty: from ``settings.plane_point`` (exact), or from the nearest meetings with the ground
    of the head's rays through ``pixels`` (N, 2), uncertain by their spread and by the move of a
    meeting under the track noise, in quadrature (the nearest of noisy meetings are drawn near by
    about that much; ``width``: the head's pixel filter, frames)."""
    origin, rays = camera.centre, camera.rays(pixels)
    if settings.plane_point is not None:
        distance = float(normal @ (np.asarray(settings.plane_point) - origin))
        if distance <= 0:
            raise TrackError(f"plane_point {settings.plane_point} is behind the camera (distance {distance:.3f} m)")
        return distance, 0.0
    contacts = max(3, math.ceil(settings.contact_share * len(rays)))
    downward = rays[rays[:, 2] < -1e-6]
    if len(downward) < contacts:
        raise TrackError(
            f"camera sees no ground: only {len(downward)} of the head's {len(rays)} rays point below the horizon "
            f"(camera height {origin[2]:.2f} m; need {contacts} ground contacts to place the working plane)"
        )
    downward_pixels = pixels[rays[:, 2] < -1e-6]
    ground = _ground_meeting(origin, downward, normal)
    chosen = np.argsort(ground)[:contacts]
    nearest = ground[chosen]
    moved = [
        _ground_meeting(origin, camera.rays(downward_pixels[chosen] + step), normal) - nearest
        for step in _pixel_steps(settings.pixel_noise, width)
    ]
    pixel_spread = float(np.sqrt(np.mean(sum(np.square(move) for move in moved))))
    return float(nearest.mean()), math.hypot(float(nearest.std()), pixel_spread)


def _ground_meeting(origin: np.ndarray, rays: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(N,) horizontal distance along ``normal`` (metres) from the camera at ``origin`` to where the
    downward ``rays`` (N, 3) meet the ground z = 0."""
    return -origin[2] * (rays @ normal) / rays[:, 2]


def _filled(points: np.ndarray, frames: np.ndarray, n_frames: int) -> np.ndarray:
    """(n_frames, k) ``points`` (len(frames), k) known at ``frames``, linearly interpolated between
    them and held beyond the first and last."""
    every = np.arange(n_frames)
    return np.stack([np.interp(every, frames, points[:, k]) for k in range(points.shape[1])], axis=1)


@dataclass(frozen=True, eq=False)
class SideChoice:
    """Each visible handle frame's side and why (see :class:`LiftedDemo`).

    Attributes:
        far: (m,) bool, the far solution taken.
        source: (m,) str, one of ``SIDE_SOURCES``.
        margin: (m,) the evidence (squared standard deviations) of the weakest zero crossing between
            the frame and the hinted side; 0 on the hinted side.
    """

    far: np.ndarray
    source: np.ndarray
    margin: np.ndarray


def choose_sides(
    near: np.ndarray, far: np.ndarray, offset: np.ndarray, offset_sigma: np.ndarray, hint: str | None
) -> SideChoice:
    """The side of each visible handle frame, from its depth offset ``offset`` (m,) metres from the
    head's foot on the ray (the near and far solutions ``near``, ``far`` (m, 3) are that far either
    side), the offset's standard uncertainty ``offset_sigma`` (m,) metres, and the user's ``hint``.

    A stretch and its mirror image are equally consistent with the image, so the side changes only
    where the offset comes within its noise of zero (a graze: a local minimum below twice its
    uncertainty). There the frames around it (``CROSSING_WINDOW`` each side, weighted by their
    uncertainty) are fitted by a quadratic in time twice: the signed offsets as a crossing (their
    sign changed after the graze) and as a bounce (unchanged); the bounce's extra weighted squared
    residual is the crossing's evidence (a crossing is a line through zero, a bounce a V with its
    tip at zero; a tangent touch is a U, which both fit). Crossings with at least
    ``SWITCH_EVIDENCE`` change the side; the stretches so separated alternate, the hinted side taken
    by the ones holding most frames.

    Raises:
        TrackError: no hint, and the two solutions more than ``NEGLIGIBLE_OFFSET`` apart in some frame:
            a mirror ambiguity.
    """
    m = len(offset)
    if hint is None and np.max(offset) >= NEGLIGIBLE_OFFSET:
        worst = int(np.argmax(offset))
        raise TrackError(
            "tracks: mirror ambiguity: one view gives a motion and its mirror image, and the image does not tell "
            f"on which side of the head the handle end is (the two sides differ by up to {2 * offset[worst]:.2f} m); "
            "say which with --handle-hint near|far (LiftSettings.handle_hint)"
        )
    sigma = np.maximum(offset_sigma, OFFSET_SIGMA_FLOOR)
    crossings, evidence = [], []
    for t in range(1, m - 1):
        if offset[t] <= offset[t - 1] and offset[t] < offset[t + 1] and offset[t] < 2 * sigma[t]:
            strength = _crossing_evidence(offset, sigma, t)
            if strength >= SWITCH_EVIDENCE:
                crossings.append(t)
                evidence.append(strength)
    parity = np.zeros(m, dtype=int)
    for t in crossings:
        parity[t:] ^= 1
    hinted = hint == "far"
    # the parity whose frames are on the hinted side: the one most frames have
    hinted_parity = int(np.sum(parity) > m / 2)
    far_chosen = np.where(parity == hinted_parity, hinted, not hinted)
    source = np.where(parity == hinted_parity, "hint", "crossing").astype("<U10")
    margin = np.zeros(m)
    bounds = [0, *crossings, m]
    for k, (start, stop) in enumerate(zip(bounds[:-1], bounds[1:])):
        if parity[start] != hinted_parity:
            edges = [evidence[j] for j in (k - 1, k) if 0 <= j < len(evidence)]
            margin[start:stop] = min(edges)
        if np.max(offset[start:stop]) < NEGLIGIBLE_OFFSET:
            source[start:stop] = "negligible"
    return SideChoice(far=far_chosen.astype(bool), source=source, margin=margin)


def _crossing_evidence(offset: np.ndarray, sigma: np.ndarray, graze: int) -> float:
    """How much worse (weighted squared residual, squared standard deviations) a quadratic in time
    fits the offsets (m,) metres around frame ``graze`` as a bounce than as a crossing
    (:func:`choose_sides`); ``sigma`` (m,) metres weighs each frame."""
    frames = np.arange(max(0, graze - CROSSING_WINDOW), min(len(offset), graze + CROSSING_WINDOW + 1))
    if len(frames) < 5:
        return 0.0
    times = (frames - graze).astype(float)
    design = np.column_stack([np.ones_like(times), times, times**2]) / sigma[frames, None]
    residuals = []
    for signs in (np.where(frames > graze, -1.0, 1.0), np.ones(len(frames))):
        target = signs * offset[frames] / sigma[frames]
        solution, *_ = np.linalg.lstsq(design, target, rcond=None)
        residuals.append(float(np.sum((design @ solution - target) ** 2)))
    return residuals[1] - residuals[0]


def _head_moves(
    camera: Camera,
    tracks: EndpointTracks,
    head_frames: np.ndarray,
    normal: np.ndarray,
    distance: float,
    distance_sigma: float,
    settings: LiftSettings,
    width: float,
) -> list[np.ndarray]:
    """The lifted head (T, 3 each) with the plane moved by its distance's uncertainty and with each
    pixel coordinate moved by the track noise left after the head's filter of ``width`` frames."""
    origin, n_frames = camera.centre, tracks.n_frames
    head_pixels = tracks.head[head_frames]

    def head_at(pixels: np.ndarray, plane: float) -> np.ndarray:
        return _filled(ray_plane_intersection(origin, camera.rays(pixels), normal, plane), head_frames, n_frames)

    return [head_at(head_pixels, distance + distance_sigma)] + [
        head_at(head_pixels + step, distance) for step in _pixel_steps(settings.pixel_noise, width)
    ]


def _handle_spreads(
    camera: Camera,
    tracks: EndpointTracks,
    handle_frames: np.ndarray,
    head: np.ndarray,
    head_moves: list[np.ndarray],
    length: float,
    settings: LiftSettings,
    width: float,
) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """For the visible handle frames, under each move of :func:`_head_moves` and of the handle's
    pixels by the track noise left after its filter of ``width`` frames: the moved rays (list of
    (m, 3)), the spread of the head's foot on the ray (m,) metres and the spread of the depth offset
    ``sqrt(q)`` (m,) metres (``q``: :func:`squared_offset`): the half-width of the image of ``q``'s
    +-1-sigma interval, which is the linear ``sigma_q / (2 sqrt(q))`` away from the tangent and
    stays finite (``sqrt(sigma_q) / 2``) where the ray grazes the tool-length sphere."""
    origin = camera.centre
    handle_pixels = tracks.handle[handle_frames]
    heads = head[handle_frames]
    rays = camera.rays(handle_pixels)
    foot, squared_depth = squared_offset(origin, rays, heads, length)
    moves = [(rays, moved[handle_frames]) for moved in head_moves]
    moves += [(camera.rays(handle_pixels + step), heads) for step in _pixel_steps(settings.pixel_noise, width)]
    foot_spread = depth_spread = np.zeros(len(handle_frames))
    for moved_rays, moved_heads in moves:
        moved_foot, moved_depth = squared_offset(origin, moved_rays, moved_heads, length)
        foot_spread = foot_spread + (moved_foot - foot) ** 2
        depth_spread = depth_spread + (moved_depth - squared_depth) ** 2
    depth_spread = np.sqrt(depth_spread)
    positive = np.maximum(squared_depth, 0.0)
    offset_spread = (np.sqrt(positive + depth_spread) - np.sqrt(np.maximum(positive - depth_spread, 0.0))) / 2
    return [moved_rays for moved_rays, _ in moves], np.sqrt(foot_spread), offset_spread


def _handle_sigma(
    camera: Camera,
    tracks: EndpointTracks,
    handle_frames: np.ndarray,
    head: np.ndarray,
    handle: np.ndarray,
    head_moves: list[np.ndarray],
    length: float,
    settings: LiftSettings,
    width: float,
) -> np.ndarray:
    """(T,) the handle end's standard uncertainty, metres, its side taken as right: its ray's
    sideways move at its range, the move of the head's foot on the ray and the depth offset's
    spread (:func:`_handle_spreads`), in quadrature; interpolated over the frames it is not seen."""
    rays = camera.rays(tracks.handle[handle_frames])
    ranges = np.sum(rays * (handle[handle_frames] - camera.centre), axis=1)
    moved_rays, foot_spread, offset_spread = _handle_spreads(
        camera, tracks, handle_frames, head, head_moves, length, settings, width
    )
    sideways = sum(np.sum(((moved - rays) * ranges[:, None]) ** 2, axis=1) for moved in moved_rays)
    seen = np.sqrt(sideways + foot_spread**2 + offset_spread**2)
    return _filled(seen[:, None], handle_frames, tracks.n_frames)[:, 0]


def _pixel_steps(noise: float, width: float) -> tuple[np.ndarray, np.ndarray]:
    """The moves (px) of a pixel's u and v by one standard deviation of the track noise left after
    a filter of ``width`` frames: ``noise`` px times the root of the sum of the squared weights of
    the Gaussian filter (white noise's share that passes it; 1 without filter)."""
    kept = 1.0
    if width > 0:
        impulse = np.zeros((16 * math.ceil(width) + 1, 1))
        impulse[len(impulse) // 2] = 1.0
        weights = _filtered(impulse, np.arange(len(impulse)), len(impulse), width)
        kept = float(np.sqrt(np.sum(weights**2)))
    return np.array([noise * kept, 0.0]), np.array([0.0, noise * kept])
