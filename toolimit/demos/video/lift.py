"""The lift: 2D endpoint tracks and a calibrated camera become a 3D demonstration.

One view cannot give depth, so the lift uses what the scene tells (measured: a full 3D lift by
reprojection error, tool length and smoothness alone was ill-posed here, 0.65-3 m off):

1. **The working plane.** The head moves in a vertical plane facing the camera (its normal is the
   camera's viewing direction made horizontal). Its distance comes from the frames where the head
   touches the ground: a head ray that points below the horizon meets the ground z = 0 at a
   horizontal distance ``d``; a head on or above the ground lies no farther than that, so the
   plane is as far as the nearest such meetings (the mean of the lowest ``contact_share`` of them).
   Or it is given: a known point of the plane (the hammer's nail).
2. **The head** is its ray's intersection with that plane (closed form).
3. **The handle end** lies on its own ray at the tool's length from the head: two solutions, the
   near one (nearer to the camera than the foot of the head on that ray) and the far one. Dynamic
   programming picks one per frame so that the handle's path is smoothest (least squared
   acceleration); where both paths are equally smooth (the mirror image of a motion seen from the
   side is as smooth as the motion), ``handle_hint`` decides, and without a hint the lift refuses
   rather than return a mirrored demonstration.
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
#: With a hint, each frame whose handle end leaves the hinted side costs this times the squared
#: separation of the two solutions (m^2, the unit of the squared accelerations): a run of frames
#: leaves the hint only where the smooth path clearly crosses to the other side. Measured on the
#: benchmark's synthetic hammer (3 px): 1e-3 (a tie-breaker) gave 10.8 deg of axis error, 1 gave 5.7.
HINT_WEIGHT = 1.0
#: The pixel filter widths (frames, Gaussian standard deviation) cross-validation chooses from:
#: 0.5 to 8 frames in steps of sqrt(2).
PIXEL_WIDTHS = tuple(0.5 * 2 ** (k / 2) for k in range(9))


@dataclass(frozen=True)
class LiftSettings:
    """How tracks are lifted to 3D (``toolimit demo lift``).

    Attributes:
        handle_hint: where the handle end is when the image cannot tell: "near" (nearer to the
            camera than the head) or "far"; None refuses a mirror ambiguity.
        tool_length: head to handle end, metres (None: the tool's registered length).
        plane_point: a world point (x, y, z metres) on the head's working plane (None: the plane
            from the frames where the head touches the ground).
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
        mirror_ratio: the mirrored handle path counts as an equal explanation when its squared
            acceleration is less than this many times the best path's.
    """

    handle_hint: str | None = None
    tool_length: float | None = None
    plane_point: tuple[float, float, float] | None = None
    contact_share: float = 0.05
    pixel_noise: float = 3.0
    smoothing: float | None = None
    offset_smoothing: float = 1.0
    min_visible_share: float = 0.5
    mirror_ratio: float = 1.5

    def __post_init__(self) -> None:
        if self.handle_hint is not None and self.handle_hint not in HANDLE_HINTS:
            raise InvalidSetting("handle_hint", f"expected near or far, got {self.handle_hint!r}")
        if self.tool_length is not None and not (math.isfinite(self.tool_length) and self.tool_length > 0):
            raise InvalidSetting("tool_length", f"must be a positive number of metres, got {self.tool_length!r}")
        if self.plane_point is not None and (
            len(self.plane_point) != 3 or not all(math.isfinite(value) for value in self.plane_point)
        ):
            raise InvalidSetting("plane_point", f"expected three finite coordinates x, y, z, got {self.plane_point!r}")
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
        if not self.mirror_ratio >= 1:
            raise InvalidSetting("mirror_ratio", f"must be at least 1, got {self.mirror_ratio!r}")


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
        plane_normal: (3,) horizontal unit normal of the working plane, pointing away from the camera.
        plane_distance: the plane's distance from the camera's centre along that normal, metres.
        hint_used: whether the handle's sides came from ``handle_hint`` (a mirror ambiguity).
        pixel_smoothing: the pixel filter's width for the head and for the handle end, frames.
    """

    demo: ToolDemo
    head_sigma: np.ndarray
    handle_sigma: np.ndarray
    head_filled: np.ndarray
    handle_filled: np.ndarray
    handle_far: np.ndarray
    plane_normal: np.ndarray
    plane_distance: float
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
            down, a camera that sees no ground, a mirror ambiguity without a hint.
    """
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
    normal = np.array([forward[0], forward[1], 0.0]) / np.linalg.norm(forward[:2])

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
    far_chosen, hint_used = _handle_sides(near, far, offset, settings)
    signed = np.where(far_chosen, offset, -offset)
    if settings.offset_smoothing > 0:
        signed = _filtered(signed[:, None], handle_frames, tracks.n_frames, settings.offset_smoothing)[handle_frames, 0]
    far_chosen = signed > 0
    foot, _ = squared_offset(origin, handle_rays, head[handle_frames], length)
    handle = _filled(_on_ray(origin, handle_rays, foot + signed), handle_frames, tracks.n_frames)
    axis = handle - head
    handle = head + length * axis / np.linalg.norm(axis, axis=1, keepdims=True)

    head_sigma, handle_sigma = _uncertainty(
        camera,
        tracks,
        head_frames,
        handle_frames,
        head,
        handle,
        normal,
        distance,
        distance_sigma,
        length,
        settings,
        widths,
    )
    demo = ToolDemo(head, handle, fps, tool, source=f"lifted from 2D tracks ({tracks.n_frames} frames)")
    return LiftedDemo(
        demo=demo,
        head_sigma=head_sigma,
        handle_sigma=handle_sigma,
        head_filled=~tracks.head_visible,
        handle_filled=~tracks.handle_visible,
        handle_far=_filled(far_chosen[:, None].astype(float), handle_frames, tracks.n_frames)[:, 0] > 0.5,
        plane_normal=normal,
        plane_distance=distance,
        hint_used=hint_used,
        pixel_smoothing=widths,
    )


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


def _smoothest_sides(near: np.ndarray, far: np.ndarray, preferred: np.ndarray | None) -> tuple[np.ndarray, float]:
    """Per frame, far (True) or near: the choice whose path has the least summed squared
    acceleration (dynamic programming over the pair of the last two choices), plus, with
    ``preferred`` (N,) bool, a tie-breaking cost for every frame that leaves it. Returns the
    choice and its acceleration cost."""
    candidates = np.stack([near, far], axis=1)  # (N, 2, 3)
    n = len(candidates)
    if n < 3:
        return np.zeros(n, dtype=bool), 0.0
    # cost[a, b]: best cost of a path whose last two choices are a (frame t-1) and b (frame t)
    bias = np.zeros((n, 2)) if preferred is None else _leave_cost(candidates, preferred)
    cost = bias[0][:, None] + bias[1][None, :]
    back = np.zeros((n, 2, 2), dtype=int)
    for t in range(2, n):
        # acceleration[a, b, c] for choices a, b, c at frames t-2, t-1, t
        acceleration = (
            candidates[t][None, None, :, :]
            - 2 * candidates[t - 1][None, :, None, :]
            + candidates[t - 2][:, None, None, :]
        )
        total = cost[:, :, None] + np.sum(acceleration**2, axis=-1) + bias[t][None, None, :]
        back[t] = np.argmin(total, axis=0)
        cost = np.min(total, axis=0)
    last = np.unravel_index(int(np.argmin(cost)), cost.shape)
    choice = np.zeros(n, dtype=int)
    choice[-2], choice[-1] = last
    for t in range(n - 1, 1, -1):
        choice[t - 2] = back[t, choice[t - 1], choice[t]]
    far_chosen = choice.astype(bool)
    return far_chosen, _acceleration_cost(np.where(far_chosen[:, None], far, near))


def _leave_cost(candidates: np.ndarray, preferred: np.ndarray) -> np.ndarray:
    """(N, 2) the cost of leaving ``preferred`` (N,) bool (True: far) at each frame, ``HINT_WEIGHT``
    times the two solutions' squared separation."""
    separation = np.sum((candidates[:, 1] - candidates[:, 0]) ** 2, axis=1)
    bias = np.zeros((len(candidates), 2))
    bias[np.arange(len(candidates)), (~preferred).astype(int)] = HINT_WEIGHT * separation
    return bias


def _acceleration_cost(path: np.ndarray) -> float:
    return float(np.sum(np.diff(path, n=2, axis=0) ** 2))


def _handle_sides(
    near: np.ndarray, far: np.ndarray, offset: np.ndarray, settings: LiftSettings
) -> tuple[np.ndarray, bool]:
    """Far (True) or near per visible handle frame, and whether the hint decided."""
    far_chosen, cost = _smoothest_sides(near, far, None)
    mirrored = _acceleration_cost(np.where(far_chosen[:, None], near, far))
    # Separations below a centimetre change nothing that matters: no ambiguity to report.
    ambiguous = mirrored <= settings.mirror_ratio * cost + 1e-12 and np.max(offset) > 0.005
    if not ambiguous:
        return far_chosen, False
    if settings.handle_hint is None:
        worst = int(np.argmax(offset))
        raise TrackError(
            "tracks: mirror ambiguity: the handle end nearer to and farther from the camera than the head are "
            f"equally smooth (squared acceleration {cost:.4g} and {mirrored:.4g} m^2; the two differ by up to "
            f"{2 * offset[worst]:.2f} m); say which with --handle-hint near|far (LiftSettings.handle_hint)"
        )
    preferred = np.full(len(near), settings.handle_hint == "far")
    far_chosen, _ = _smoothest_sides(near, far, preferred)
    return far_chosen, True


def _uncertainty(
    camera: Camera,
    tracks: EndpointTracks,
    head_frames: np.ndarray,
    handle_frames: np.ndarray,
    head: np.ndarray,
    handle: np.ndarray,
    normal: np.ndarray,
    distance: float,
    distance_sigma: float,
    length: float,
    settings: LiftSettings,
    widths: tuple[float, float],
) -> tuple[np.ndarray, np.ndarray]:
    """(T,) standard uncertainty of head and handle end, metres: the changes caused by moving each
    pixel coordinate of either end by the track noise left after that end's filter of ``widths``
    (head, handle end; :func:`_pixel_steps`) and the plane by its
    distance's uncertainty, added in quadrature (finite
    differences of the lift itself); interpolated over the frames an end is not seen.

    The handle end's: its ray's sideways move at its range, the move of the head's foot on the ray,
    and the spread of its depth offset ``sqrt(q)`` from the foot (``q``: :func:`squared_offset`,
    moved by both ends' pixels and the plane): the half-width of the image of ``q``'s +-1-sigma
    interval, which is the linear ``sigma_q / (2 sqrt(q))`` away from the tangent and stays finite
    (``sqrt(sigma_q) / 2``) where the ray grazes the tool-length sphere, where a finite difference
    clamped at the tangent reports almost nothing."""
    origin, n_frames = camera.centre, tracks.n_frames
    head_steps, handle_steps = (_pixel_steps(settings.pixel_noise, width) for width in widths)
    head_pixels = tracks.head[head_frames]

    def head_at(pixels: np.ndarray, plane: float) -> np.ndarray:
        return _filled(ray_plane_intersection(origin, camera.rays(pixels), normal, plane), head_frames, n_frames)

    head_moves = [head_at(head_pixels, distance + distance_sigma)] + [
        head_at(head_pixels + step, distance) for step in head_steps
    ]
    head_sigma = np.sqrt(sum(np.sum((moved - head) ** 2, axis=1) for moved in head_moves))

    handle_pixels = tracks.handle[handle_frames]
    heads = head[handle_frames]
    rays = camera.rays(handle_pixels)
    foot, squared_depth = squared_offset(origin, rays, heads, length)
    ranges = np.sum(rays * (handle[handle_frames] - origin), axis=1)
    moves = [(rays, moved[handle_frames]) for moved in head_moves]
    moves += [(camera.rays(handle_pixels + step), heads) for step in handle_steps]
    sideways = foot_spread = depth_spread = np.zeros(len(handle_frames))
    for moved_rays, moved_heads in moves:
        moved_foot, moved_depth = squared_offset(origin, moved_rays, moved_heads, length)
        sideways = sideways + np.sum(((moved_rays - rays) * ranges[:, None]) ** 2, axis=1)
        foot_spread = foot_spread + (moved_foot - foot) ** 2
        depth_spread = depth_spread + (moved_depth - squared_depth) ** 2
    depth_spread = np.sqrt(depth_spread)
    positive = np.maximum(squared_depth, 0.0)
    offset_spread = (np.sqrt(positive + depth_spread) - np.sqrt(np.maximum(positive - depth_spread, 0.0))) / 2
    seen = np.sqrt(sideways + foot_spread + offset_spread**2)
    return head_sigma, _filled(seen[:, None], handle_frames, n_frames)[:, 0]


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
