"""The working plane's depth from the tool's length, measured against the ground contacts.

The lift places the vertical working plane at the depth where the head's rays meet the ground
(``lift_tracks``). The alternative measured here: if both ends lay in the plane at depth ``d``,
the tool's apparent length would grow linearly with ``d``, so each frame where both ends are seen
gives ``d_i = L / |r_head / (r_head . n) - r_handle / (r_handle . n)|`` (``L`` the tool's length,
``r`` the ends' unit rays, ``n`` the plane's normal); a tool leaving the plane looks shorter, so
``d_i`` would bound its depth from beyond, tightly where the tool is parallel to the image. Fixed
estimators, chosen before the figures: the 5th and 10th percentile of ``d_i``, its minimum, and
the larger of the ground depth and each percentile. Same cameras, noise (3 px), dropped frames,
hints and seeds as ``benchmarks/video_lift.py``; the hammers' planes are given there (nail, first
impact), so their rows show what each estimate would do without that point. Also printed, from the
noise-free tracks: the share of frames whose ``d_i`` is nearer than that frame's true head depth
(the bound broken: perspective and the head's own departure from the mean plane) and the
smallest depth offset between the tool's ends (how close to parallel to the image it comes).

    python benchmarks/video_lift_plane_from_length.py [--shared ../shared]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from video_lift import DROP, NOISE_PX, REPO, SEEDS, axis_degrees, cases

from toolimit.demos import ToolDemo
from toolimit.demos.video import (
    Camera,
    EndpointTracks,
    LiftSettings,
    handle_side,
    lift_tracks,
    perturbed,
    project_demo,
    side_camera,
)
from toolimit.demos.video.lift import smoothed
from toolimit.tools import tool_spec

#: The lift's pixel filter when these figures were measured (1 frame for both ends; the lift now
#: chooses each end's by cross-validation), kept so that the history's figures stay reproducible.
PIXEL_SMOOTHING = 1.0


def length_depths(tracks: EndpointTracks, camera: Camera, normal: np.ndarray, length: float) -> np.ndarray:
    """(N,) per frame where both ends are seen, the plane depth (metres along ``normal``) at which
    the two ends' ray-plane points are ``length`` metres apart."""
    both = tracks.head_visible & tracks.handle_visible
    head, handle = camera.rays(tracks.head[both]), camera.rays(tracks.handle[both])
    per_unit_depth = head / (head @ normal)[:, None] - handle / (handle @ normal)[:, None]
    return length / np.linalg.norm(per_unit_depth, axis=1)


def estimates(tracks: EndpointTracks, camera: Camera, truth: ToolDemo, hint: str) -> dict[str, float]:
    """Each estimator's plane depth (metres) from ``tracks``."""
    settings = LiftSettings(handle_hint=hint, pixel_noise=NOISE_PX, smoothing=PIXEL_SMOOTHING)
    ground_lift = lift_tracks(tracks, camera, truth.tool, truth.fps, settings)
    ground = ground_lift.plane_distance
    depths = length_depths(
        smoothed(tracks, (PIXEL_SMOOTHING, PIXEL_SMOOTHING)),
        camera,
        ground_lift.plane_normal,
        tool_spec(truth.tool).length,
    )
    q05, q10 = float(np.quantile(depths, 0.05)), float(np.quantile(depths, 0.10))
    return {
        "ground contacts": ground,
        "length, 5th pct": q05,
        "length, 10th pct": q10,
        "length, minimum": float(depths.min()),
        "max(ground, 5th)": max(ground, q05),
        "max(ground, 10th)": max(ground, q10),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=REPO.parent / "shared")
    args = parser.parse_args()
    print(f"3 px noise, {DROP:.0%} of frames dropped; mean over {len(SEEDS)} seeds [worst seed]")
    for name, truth, plane_point, handle_known in cases(args.shared):
        camera = side_camera(truth.head)
        exact = project_demo(truth, camera)
        hint = handle_side(truth, camera)
        normal = lift_tracks(exact, camera, truth.tool, truth.fps, LiftSettings(handle_hint=hint)).plane_normal
        true_depth = (truth.head - camera.centre) @ normal
        both = exact.head_visible & exact.handle_visible
        broken = np.mean(length_depths(exact, camera, normal, tool_spec(truth.tool).length) < true_depth[both])
        offset = np.abs((truth.handle - truth.head) @ normal)
        print(
            f"== {name}: true head depth {true_depth.mean():.3f} m (min {true_depth.min():.3f}, max "
            f"{true_depth.max():.3f}); ends' depth offset at least {100 * offset.min():.1f} cm of "
            f"{100 * tool_spec(truth.tool).length:.0f}; bound broken in {broken:.0%} of the noise-free frames"
        )
        rows: dict[str, list[tuple[float, float, float]]] = {}
        for seed in SEEDS:
            tracks = perturbed(exact, NOISE_PX, DROP, seed)
            depths = estimates(tracks, camera, truth, hint)
            if plane_point is not None:
                depths = {"given point": float(normal @ (np.asarray(plane_point) - camera.centre)), **depths}
            for key, depth in depths.items():
                point = (camera.centre + depth * normal).tolist()
                settings = LiftSettings(
                    handle_hint=hint,
                    pixel_noise=NOISE_PX,
                    plane_point=(point[0], point[1], point[2]),
                    smoothing=PIXEL_SMOOTHING,
                )
                lifted = lift_tracks(tracks, camera, truth.tool, truth.fps, settings).demo
                head = float(np.mean(np.linalg.norm(lifted.head - truth.head, axis=1)))
                rows.setdefault(key, []).append((depth, head, float(np.mean(axis_degrees(lifted, truth)))))
        for key, values in rows.items():
            table = np.array(values)
            axis = (
                f"axis {table[:, 2].mean():5.2f} deg [{table[:, 2].max():5.2f}]"
                if handle_known
                else "axis: no true handle"
            )
            print(
                f"  {key:18s} depth {table[:, 0].mean():.3f} m: head {100 * table[:, 1].mean():6.1f} cm "
                f"[{100 * table[:, 1].max():6.1f}], {axis}"
            )


if __name__ == "__main__":
    main()
