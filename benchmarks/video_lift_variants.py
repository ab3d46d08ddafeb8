"""The lift's two missed targets, measured against its alternatives (docs/results/video_lift.md, docs/history.md).

1. The spade example's head error comes from the working plane's depth. Printed for each trajectory:
   each contact event's nearest ray-ground meeting (an event: a run of frames whose noise-free
   meeting is within 10 cm of the nearest), the true head depth and height there, the plane depth
   at which the lower of the two lifted ends touches the ground (both ends' contacts), and the plane
   depth the head error's target needs (the noise-free lift through planes 1 cm apart).
2. The synthetic hammer's and spade video 1's tool axis come from the noise on the handle's depth
   offset. The alternatives to the lift's 1-frame Gaussian filters of the pixel tracks and of the
   handle's signed depth offset as they were before this comparison (``LiftSettings(smoothing=1.0,
   offset_smoothing=1.0)``), each fixed before its figures (the lift kept ``gcv`` pixels):
   - ``gcv``: each filter's width chosen per motion by generalised cross-validation over the grid
     ``WIDTHS`` (pixels: each end's two coordinates together; offset: the signed offsets);
   - ``discrepancy``: the widest width of ``WIDTHS`` whose residual the stated pixel noise explains,
     ``sum(r^2 / sigma^2) <= k (n - tr S)`` (Morozov's principle; offset: offsets from the raw handle
     pixels, compared in the squared offset's domain, where the noise is near Gaussian, with both
     ends' noise);
   - ``debiased``: the lift's filtered signed offset, its magnitude replaced by the offset whose
     expected square-root estimate under the squared offset's noise it is (``debiased_offset``);
   - ``ici``: the signed offset filtered with a width per frame, by intersecting confidence
     intervals (``ici_smoothed``: from 1 to 8 frames, each frame's noise from the pixel noise);
   - ``kalman``: the signed offset by a Rauch-Tung-Striebel smoother of a random-acceleration model,
     each frame's measurement variance from the pixel noise (the half-width used by the lift's
     uncertainty, finite at the tangent), the process noise by maximum marginal likelihood over
     ``PROCESS_NOISES``; the offsets from the smoothed or from the raw handle pixels;
   - ``bayes``: the signed offset as the posterior mean of a discrete smoother (forward-backward on
     a grid of offsets along each frame's handle ray): emission from both ends' pixel noise on the
     radial pixel residual of the tool-length sphere's point in that direction, random-walk steps
     whose size comes from maximum marginal likelihood over ``STEPS``, the mean taken on the side
     the near/far choice took; from the smoothed or the raw handle pixels;
   - a diagnostic, not a choice: fixed widths for the two filters on a grid.
   Same cameras, 3 px noise, 5 % dropped frames, hints, planes and seeds as
   ``benchmarks/video_lift.py``; mean over seeds [worst seed]. ``discrepancy`` also with exact
   tracks lifted as if they had 3 px of noise, and with 8 px; ``gcv`` pixels also on exact tracks and 8 px.

    python benchmarks/video_lift_variants.py [--shared ../shared] [--out benchmarks/results/video_lift]
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from video_lift import DROP, NOISE_PX, REPO, SEEDS, cases

from toolimit.demos import ToolDemo
from toolimit.demos.video import Camera, EndpointTracks, LiftSettings, handle_side, perturbed, project_demo, side_camera
from toolimit.demos.video import lift as lift_module
from toolimit.tools import tool_spec

#: Filter widths (frames) the width rules choose from: 0.5 to 8 in steps of sqrt(2).
WIDTHS = [0.5 * 2 ** (k / 2) for k in range(9)]
#: Process noise (m^2 per frame^3) of the Kalman smoother's random-acceleration model.
PROCESS_NOISES = [10.0 ** (k / 2) for k in range(-14, 1)]
#: Random-walk step (m per frame) of the discrete smoother.
STEPS = [0.0025 * 2 ** (k / 2) for k in range(11)]
#: Half-width, in standard deviations, of the intervals the ICI rule intersects (the usual 2).
ICI_GAMMA = 2.0
#: The discrete smoother's offsets: this many, evenly from -L to L.
GRID = 161


def smoother_matrix(frames: np.ndarray, n_frames: int, width: float) -> np.ndarray:
    """(m, m) the lift's time filter (gaps bridged, ends padded) from the values at ``frames`` to itself."""
    return lift_module._filtered(np.eye(len(frames)), frames, n_frames, width)[frames]


def gcv_width(values: np.ndarray, frames: np.ndarray, n_frames: int) -> float:
    """The width of ``WIDTHS`` with the least generalised cross-validation score for ``values`` (m, k)."""
    scores = []
    for width in WIDTHS:
        matrix = smoother_matrix(frames, n_frames, width)
        residual = values - matrix @ values
        scores.append(len(frames) * np.sum(residual**2) / (len(frames) - np.trace(matrix)) ** 2)
    return WIDTHS[int(np.argmin(scores))]


def discrepancy_width(values: np.ndarray, frames: np.ndarray, n_frames: int, sigma: np.ndarray) -> float:
    """The widest width of ``WIDTHS`` whose residual ``sigma`` (m, 1) explains (0 without noise)."""
    if not np.all(sigma > 0):
        return 0.0
    chosen = WIDTHS[0]
    for width in WIDTHS:
        matrix = smoother_matrix(frames, n_frames, width)
        residual = (values - matrix @ values) / sigma
        if np.sum(residual**2) > values.shape[1] * (len(frames) - np.trace(matrix)):
            break
        chosen = width
    return chosen


def kalman_smoothed(values: np.ndarray, variances: np.ndarray, frames: np.ndarray, n_frames: int) -> np.ndarray:
    """(n_frames,) RTS-smoothed ``values`` (m,) measured at ``frames`` with ``variances`` (m,), under a
    random-acceleration model whose process noise maximises the marginal likelihood."""

    def run(process: float) -> tuple[np.ndarray, float]:
        step = np.array([[1.0, 1.0], [0.0, 1.0]])
        noise = process * np.array([[1 / 3, 1 / 2], [1 / 2, 1.0]])
        measured = dict(zip(frames.tolist(), range(len(frames))))
        state, covariance = np.array([values[0], 0.0]), np.diag([1e2, 1e2])
        predicted, filtered, likelihood = [], [], 0.0
        for t in range(n_frames):
            if t > 0:
                state, covariance = step @ state, step @ covariance @ step.T + noise
            predicted.append((state, covariance))
            if t in measured:
                i = measured[t]
                spread = covariance[0, 0] + variances[i]
                innovation = values[i] - state[0]
                if i > 1:  # the first two measurements set the state
                    likelihood -= 0.5 * (np.log(2 * np.pi * spread) + innovation**2 / spread)
                gain = covariance[:, 0] / spread
                state, covariance = state + gain * innovation, covariance - np.outer(gain, covariance[0])
            filtered.append((state, covariance))
        smooth = np.zeros(n_frames)
        state = filtered[-1][0]
        smooth[-1] = state[0]
        for t in range(n_frames - 2, -1, -1):
            gain = filtered[t][1] @ step.T @ np.linalg.inv(predicted[t + 1][1])
            state = filtered[t][0] + gain @ (state - predicted[t + 1][0])
            smooth[t] = state[0]
        return smooth, likelihood

    best = max(PROCESS_NOISES, key=lambda process: run(process)[1])
    return run(best)[0]


def forward_backward(log_emission: np.ndarray, grid: np.ndarray, step: float) -> tuple[np.ndarray, float]:
    """Posterior (T, G) over ``grid`` of a random walk with Gaussian steps of ``step`` under
    ``log_emission`` (T, G), and the log marginal likelihood."""
    transition = np.exp(-0.5 * ((grid[:, None] - grid[None, :]) / step) ** 2)
    transition /= transition.sum(axis=1, keepdims=True)
    emission = np.exp(log_emission - log_emission.max(axis=1, keepdims=True))
    n = len(emission)
    alpha, scale = np.zeros_like(emission), np.zeros(n)
    for t in range(n):
        unnormalised = (emission[0] / emission.shape[1]) if t == 0 else (alpha[t - 1] @ transition) * emission[t]
        scale[t] = unnormalised.sum()
        alpha[t] = unnormalised / scale[t]
    beta = np.ones_like(emission)
    for t in range(n - 2, -1, -1):
        beta[t] = transition @ (emission[t + 1] * beta[t + 1]) / scale[t + 1]
    posterior = alpha * beta
    return posterior / posterior.sum(axis=1, keepdims=True), float(np.sum(np.log(scale)))


def debiased_offset(magnitude: np.ndarray, squared_sigma: np.ndarray) -> np.ndarray:
    """(m,) the depth offset ``sqrt(q)`` whose expected estimate ``E sqrt(max(q + e, 0))``, ``e`` ~
    N(0, ``squared_sigma``^2), equals ``magnitude`` (m,) (0 where even q = 0 expects more): the
    bias of the square root of a noisy squared offset removed (upwards near the tangent, where the
    clamp at 0 dominates; downwards beyond it, where the root's concavity does)."""
    z = np.linspace(-8.0, 8.0, 4001)
    weight = np.exp(-0.5 * z**2)
    weight /= weight.sum()
    x = np.concatenate([np.linspace(0.0, 10.0, 401), np.linspace(10.5, 400.0, 800)])  # q / sigma
    expected = np.sqrt(np.maximum(x[:, None] + z[None, :], 0.0)) @ weight  # E sqrt(max(x + Z, 0)), increasing
    ratio = np.interp(magnitude / np.sqrt(squared_sigma), expected, x, left=0.0, right=np.nan)
    ratio = np.where(np.isnan(ratio), (magnitude / np.sqrt(squared_sigma)) ** 2, ratio)
    return np.sqrt(ratio * squared_sigma)


def ici_smoothed(values: np.ndarray, sigma: np.ndarray, frames: np.ndarray, n_frames: int, width: float) -> np.ndarray:
    """(m,) ``values`` (m,) at ``frames``, each filtered with its own width: the widest of ``width``
    times 1 to 8 (steps of sqrt(2)) whose interval +-``ICI_GAMMA`` standard deviations (from the
    values' ``sigma`` (m,) through the filter's weights) still meets every narrower one's
    (intersection of confidence intervals: a wider filter is taken while its estimate agrees
    with the narrower ones within their noise)."""
    lower, upper = np.full(len(frames), -np.inf), np.full(len(frames), np.inf)
    chosen, open_ = values.copy(), np.ones(len(frames), dtype=bool)
    for k in range(7):
        matrix = smoother_matrix(frames, n_frames, width * 2 ** (k / 2))
        estimate, spread = matrix @ values, np.sqrt(matrix**2 @ sigma**2)
        lower, upper = (
            np.maximum(lower, estimate - ICI_GAMMA * spread),
            np.minimum(upper, estimate + ICI_GAMMA * spread),
        )
        open_ &= lower <= upper
        chosen = np.where(open_, estimate, chosen)
    return chosen


@dataclass(frozen=True)
class Variant:
    """How the pixel tracks and the handle's signed depth offset are filtered.

    Attributes:
        pixels: "fixed" (``widths[0]`` frames), "gcv" or "discrepancy".
        offset: "fixed" (``widths[1]`` frames; 0: none), "gcv", "discrepancy", "ici", "kalman" or "bayes".
        handle_pixels: the handle's rays from the "smoothed" or the "raw" pixels.
        widths: the fixed filters' widths (frames), pixels and offset.
    """

    pixels: str
    offset: str
    handle_pixels: str = "smoothed"
    widths: tuple[float, float] = (1.0, 1.0)

    def smooth_tracks(self, tracks: EndpointTracks, settings: LiftSettings) -> EndpointTracks:
        ends = {}
        for name in ("head", "handle"):
            seen = np.flatnonzero(getattr(tracks, f"{name}_visible"))
            values = getattr(tracks, name)[seen]
            width = self.widths[0]
            if self.pixels == "gcv":
                width = gcv_width(values, seen, tracks.n_frames)
            elif self.pixels == "discrepancy":
                width = discrepancy_width(values, seen, tracks.n_frames, np.full((len(seen), 1), settings.pixel_noise))
            if width > 0:
                ends[name] = lift_module._filtered(values, seen, tracks.n_frames, width)
            else:
                ends[name] = lift_module._filled(values, seen, tracks.n_frames)
        return replace(tracks, **ends)


def lift(raw: EndpointTracks, camera: Camera, truth: ToolDemo, settings: LiftSettings, variant: Variant):
    """(head, handle) (T, 3) each: ``lift_tracks``' head and handle end with ``variant``'s filters."""
    length = tool_spec(truth.tool).length
    tracks = variant.smooth_tracks(raw, settings)
    origin, forward = camera.centre, camera.rotation[:, 2]
    normal = np.array([forward[0], forward[1], 0.0]) / np.linalg.norm(forward[:2])
    head_frames = np.flatnonzero(tracks.head_visible)
    distance, _ = lift_module._plane_distance(camera, tracks.head[head_frames], normal, settings, variant.widths[0])
    head_rays = camera.rays(tracks.head[head_frames])
    head = lift_module._filled(
        lift_module.ray_plane_intersection(origin, head_rays, normal, distance), head_frames, tracks.n_frames
    )
    frames = np.flatnonzero(tracks.handle_visible)
    pixels = (raw if variant.handle_pixels == "raw" else tracks).handle[frames]
    rays = camera.rays(pixels)
    near, far, offset = lift_module.handle_candidates(origin, rays, head[frames], length)
    foot, squared = lift_module.squared_offset(origin, rays, head[frames], length)
    # the noise left on the pixels by the fixed filter (the offset's variants keep it)
    kept = lift_module._pixel_steps(settings.pixel_noise, variant.widths[0])[0][0]
    noise = settings.pixel_noise if variant.handle_pixels == "raw" else kept

    def lifted_head(step: np.ndarray) -> np.ndarray:
        moved_rays = camera.rays(tracks.head[head_frames] + step)
        moved = lift_module.ray_plane_intersection(origin, moved_rays, normal, distance)
        return lift_module._filled(moved, head_frames, tracks.n_frames)[frames]

    def squared_spread(handle_pixels: np.ndarray, handle_noise: float) -> tuple[np.ndarray, np.ndarray]:
        """The squared offset (m,) from ``handle_pixels`` and its standard deviation under both ends' noise."""
        squared = lift_module.squared_offset(origin, camera.rays(handle_pixels), head[frames], length)[1]
        spread = np.zeros(len(frames))
        for step in (np.array([1.0, 0.0]), np.array([0.0, 1.0])):
            moved_rays = camera.rays(handle_pixels + handle_noise * step)
            spread += (lift_module.squared_offset(origin, moved_rays, head[frames], length)[1] - squared) ** 2
            moved_head = lifted_head(kept * step)
            spread += (
                lift_module.squared_offset(origin, camera.rays(handle_pixels), moved_head, length)[1] - squared
            ) ** 2
        return squared, np.sqrt(spread)

    # the sides follow the hint, moved only at a clear zero crossing, judged with the
    # offset's spread as the lift computes it (the committed variants.json predates this choice)
    positive, spread = np.maximum(squared, 0.0), squared_spread(pixels, noise)[1]
    offset_sigma = (np.sqrt(positive + spread) - np.sqrt(np.maximum(positive - spread, 0.0))) / 2
    far_chosen = lift_module.choose_sides(near, far, offset, offset_sigma, settings.handle_hint).far
    signed = np.where(far_chosen, offset, -offset)
    if variant.offset == "fixed" and variant.widths[1] > 0:
        signed = lift_module._filtered(signed[:, None], frames, tracks.n_frames, variant.widths[1])[frames, 0]
    elif variant.offset == "gcv":
        width = gcv_width(signed[:, None], frames, tracks.n_frames)
        signed = lift_module._filtered(signed[:, None], frames, tracks.n_frames, width)[frames, 0]
    elif variant.offset == "discrepancy":
        squared, squared_sigma = squared_spread(pixels, noise)
        chosen = WIDTHS[0]
        for width in WIDTHS:
            matrix = smoother_matrix(frames, tracks.n_frames, width)
            if np.sum(((squared - (matrix @ signed) ** 2) / squared_sigma) ** 2) > len(frames) - np.trace(matrix):
                break
            chosen = width
        signed = lift_module._filtered(signed[:, None], frames, tracks.n_frames, chosen)[frames, 0]
    elif variant.offset == "debiased":
        signed = lift_module._filtered(signed[:, None], frames, tracks.n_frames, variant.widths[1])[frames, 0]
        squared, squared_sigma = squared_spread(pixels, noise)
        signed = np.sign(signed) * debiased_offset(np.abs(signed), squared_sigma)
    elif variant.offset == "ici":
        squared, squared_sigma = squared_spread(pixels, noise)
        positive = np.maximum(squared, 0.0)
        half_width = (np.sqrt(positive + squared_sigma) - np.sqrt(np.maximum(positive - squared_sigma, 0.0))) / 2
        signed = ici_smoothed(signed, half_width, frames, tracks.n_frames, variant.widths[1])
    elif variant.offset == "kalman":
        squared, squared_sigma = squared_spread(pixels, noise)
        positive = np.maximum(squared, 0.0)
        half_width = (np.sqrt(positive + squared_sigma) - np.sqrt(np.maximum(positive - squared_sigma, 0.0))) / 2
        signed = kalman_smoothed(signed, half_width**2, frames, tracks.n_frames)[frames]
    elif variant.offset == "bayes":
        ray_distance = np.sqrt(np.maximum(length**2 - squared, 0.0))
        grid = np.linspace(-length, length, GRID)
        reach = np.sqrt(ray_distance[:, None] ** 2 + grid[None, :] ** 2)
        depth = (head[frames] - origin) @ camera.rotation[:, 2]
        radial_px = (reach - length) * ray_distance[:, None] / np.maximum(reach, 1e-9) * camera.K[0, 0] / depth[:, None]
        log_emission = np.zeros((tracks.n_frames, GRID))
        log_emission[frames] = -0.5 * radial_px**2 / (noise**2 + kept**2)  # both ends' noise
        best = max(STEPS, key=lambda step: forward_backward(log_emission, grid, step)[1])
        posterior = forward_backward(log_emission, grid, best)[0][frames]
        posterior = posterior * np.where(far_chosen[:, None], grid >= 0, grid <= 0)
        signed = (posterior @ grid) / np.maximum(posterior.sum(axis=1), 1e-300)
    handle = lift_module._filled(lift_module._on_ray(origin, rays, foot + signed), frames, tracks.n_frames)
    axis = handle - head
    return head, head + length * axis / np.linalg.norm(axis, axis=1, keepdims=True)


def measure(variant: Variant, true_noise: float, stated_noise: float, shared: Path) -> dict[str, dict[str, float]]:
    """Per trajectory with a known handle: mean and worst-seed head error (cm) and axis error (deg)."""
    rows = {}
    for name, truth, plane_point, handle_known in cases(shared):
        camera = side_camera(truth.head)
        exact = project_demo(truth, camera)
        settings = LiftSettings(
            handle_hint=handle_side(truth, camera), plane_point=plane_point, pixel_noise=stated_noise
        )
        heads, axes = [], []
        for seed in SEEDS if true_noise > 0 else [0]:
            tracks = perturbed(exact, true_noise, DROP, seed) if true_noise > 0 else exact
            head, handle = lift(tracks, camera, truth, settings, variant)
            axis = (handle - head) / np.linalg.norm(handle - head, axis=1, keepdims=True)
            heads.append(100 * np.mean(np.linalg.norm(head - truth.head, axis=1)))
            axes.append(np.mean(np.degrees(np.arccos(np.clip(np.sum(axis * truth.axis, axis=1), -1.0, 1.0)))))
        row = {"head_cm": float(np.mean(heads)), "head_cm_worst": float(np.max(heads))}
        if handle_known:
            row |= {"axis_deg": float(np.mean(axes)), "axis_deg_worst": float(np.max(axes))}
        rows[name] = row
    return rows


def lowest_end_plane(tracks: EndpointTracks, camera: Camera, truth: ToolDemo, normal: np.ndarray) -> float:
    """The plane depth (m, bisection on 2.5 to 5 m) at which the lower of the lifted tool's two ends
    just touches the ground: both ends' ground contacts (the lowest end falls as the plane recedes)."""
    hint = handle_side(truth, camera)
    near, far = 2.5, 5.0
    for _ in range(40):
        middle = (near + far) / 2
        point = camera.centre + middle * normal
        settings = LiftSettings(handle_hint=hint, plane_point=(float(point[0]), float(point[1]), float(point[2])))
        lifted = lift_module.lift_tracks(tracks, camera, truth.tool, truth.fps, settings).demo
        if min(lifted.head[:, 2].min(), lifted.handle[:, 2].min()) > 0:
            near = middle
        else:
            far = middle
    return near


def contact_events(shared: Path) -> None:
    """Print each spade's contact events and the plane depth its head target needs (noise-free)."""
    for name, truth, plane_point, _ in cases(shared):
        if plane_point is not None:
            continue
        camera = side_camera(truth.head)
        forward = camera.rotation[:, 2]
        normal = np.array([forward[0], forward[1], 0.0]) / np.linalg.norm(forward[:2])
        depth = (truth.head - camera.centre) @ normal
        height = camera.centre[2]
        meeting = np.where(truth.head[:, 2] < height, depth * height / (height - truth.head[:, 2]), np.inf)
        close = np.flatnonzero(meeting < meeting.min() + 0.10)
        events = np.split(close, np.flatnonzero(np.diff(close) > 1) + 1)
        print(f"== {name}: mean head depth {depth.mean():.3f} m")
        for event in events:
            nearest = event[np.argmin(meeting[event])]
            print(
                f"  contact frames {event[0]}-{event[-1]}: nearest ground meeting {meeting[nearest]:.3f} m at frame "
                f"{nearest}, where the head is {depth[nearest]:.3f} m deep and {100 * truth.head[nearest, 2]:+.1f} cm high"
            )
        exact = project_demo(truth, camera)
        hint = handle_side(truth, camera)
        errors = []
        for plane in np.arange(3.20, 3.80, 0.01):
            point = camera.centre + plane * normal
            settings = LiftSettings(handle_hint=hint, plane_point=(float(point[0]), float(point[1]), float(point[2])))
            lifted = lift_module.lift_tracks(exact, camera, truth.tool, truth.fps, settings).demo
            errors.append((plane, 100 * float(np.mean(np.linalg.norm(lifted.head - truth.head, axis=1)))))
        lowest = []
        for seed in SEEDS:
            tracks = perturbed(exact, NOISE_PX, DROP, seed)
            plane = lowest_end_plane(tracks, camera, truth, normal)
            point = camera.centre + plane * normal
            settings = LiftSettings(handle_hint=hint, plane_point=(float(point[0]), float(point[1]), float(point[2])))
            lifted = lift_module.lift_tracks(tracks, camera, truth.tool, truth.fps, settings).demo
            lowest.append((plane, 100 * float(np.mean(np.linalg.norm(lifted.head - truth.head, axis=1)))))
        heights = (100 * truth.head[:, 2].min(), 100 * truth.handle[:, 2].min())
        print(
            f"  lowest head {heights[0]:+.1f} cm, lowest handle end {heights[1]:+.1f} cm; the plane where the lower "
            f"lifted end touches the ground, 3 px: {np.mean([p for p, _ in lowest]):.3f} m, head error "
            f"{np.mean([e for _, e in lowest]):.1f} cm [{np.max([e for _, e in lowest]):.1f}]"
        )
        within = [plane for plane, error in errors if error <= 18.0]
        best = min(errors, key=lambda pair: pair[1])
        print(
            f"  noise-free head error <= 18 cm for plane depths {min(within):.2f} to {max(within):.2f} m; "
            f"least {best[1]:.1f} cm at {best[0]:.2f} m"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=REPO.parent / "shared")
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" / "video_lift")
    args = parser.parse_args()
    contact_events(args.shared)
    variants = {
        "1-frame lift (pixels 1, offset 1)": (Variant("fixed", "fixed"), NOISE_PX, NOISE_PX),
        "gcv offset": (Variant("fixed", "gcv"), NOISE_PX, NOISE_PX),
        "gcv pixels": (Variant("gcv", "fixed"), NOISE_PX, NOISE_PX),
        "gcv both": (Variant("gcv", "gcv"), NOISE_PX, NOISE_PX),
        "gcv pixels, exact tracks": (Variant("gcv", "fixed"), 0.0, NOISE_PX),
        "gcv pixels, 8 px": (Variant("gcv", "fixed"), 8.0, 8.0),
        "discrepancy offset, raw handle pixels": (Variant("fixed", "discrepancy", "raw"), NOISE_PX, NOISE_PX),
        "discrepancy pixels": (Variant("discrepancy", "fixed"), NOISE_PX, NOISE_PX),
        "discrepancy both, raw handle pixels": (Variant("discrepancy", "discrepancy", "raw"), NOISE_PX, NOISE_PX),
        "1-frame lift, exact tracks told 3 px": (Variant("fixed", "fixed"), 0.0, NOISE_PX),
        "discrepancy pixels, exact tracks told 3 px": (Variant("discrepancy", "fixed"), 0.0, NOISE_PX),
        "1-frame lift, 8 px": (Variant("fixed", "fixed"), 8.0, 8.0),
        "discrepancy pixels, 8 px": (Variant("discrepancy", "fixed"), 8.0, 8.0),
        "debiased offset": (Variant("fixed", "debiased"), NOISE_PX, NOISE_PX),
        "ici offset": (Variant("fixed", "ici"), NOISE_PX, NOISE_PX),
        "kalman offset": (Variant("fixed", "kalman"), NOISE_PX, NOISE_PX),
        "kalman offset, raw handle pixels": (Variant("fixed", "kalman", "raw"), NOISE_PX, NOISE_PX),
        "bayes offset": (Variant("fixed", "bayes"), NOISE_PX, NOISE_PX),
        "bayes offset, raw handle pixels": (Variant("fixed", "bayes", "raw"), NOISE_PX, NOISE_PX),
    }
    for pixels in (0.5, 1.0, 1.5, 2.0):
        for offset in (0.0, 1.0, 2.0, 3.0):
            label = f"fixed widths: pixels {pixels}, offset {offset} (diagnostic)"
            variants[label] = (Variant("fixed", "fixed", widths=(pixels, offset)), NOISE_PX, NOISE_PX)
    print(f"mean over {len(SEEDS)} seeds [worst seed]; {DROP:.0%} of frames dropped")
    results = {}
    for label, (variant, true_noise, stated_noise) in variants.items():
        rows = measure(variant, true_noise, stated_noise, args.shared)
        results[label] = rows
        cells = []
        for name, row in rows.items():
            cell = f"{name[:12]} {row['head_cm']:5.1f} cm"
            if "axis_deg" in row:
                cell += f" {row['axis_deg']:5.2f} [{row['axis_deg_worst']:5.2f}] deg"
            cells.append(cell)
        print(f"{label:44s} | " + " | ".join(cells))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "variants.json").write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
