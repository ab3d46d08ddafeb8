"""A scene seen in one plane as an SVG picture (equal scale on both axes, metres), without matplotlib.

Draws what a scene's ``snapshot()`` holds, whatever the scene, by the arrays' shapes (world frame,
m): (K, 2, 3) arrays are segments (walls, the tool's segments, a board's corners), (N, 3) arrays are
points (sand grains, stalks, a nail's top); other entries are left out. Named paths (N, 3) (the
tool head's path) are added as lines, named points (keypoints) as markers, named ground rectangles
(a scene's ``footprints``) as outlines. In the vertical x-z plane the ground (z = 0) is drawn; in
the x-y plane the picture is a view from above.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from toolimit.viz.svg_plot import Series, line_plot_svg, outline

#: Plane name -> the world axes it shows (horizontal, vertical).
PLANES = {"xz": (0, 2), "xy": (0, 1)}


def scene_plane_svg(
    snapshot: Mapping[str, np.ndarray],
    title: str,
    paths: Mapping[str, np.ndarray] | None = None,
    markers: Mapping[str, np.ndarray] | None = None,
    plane: str = "xz",
    footprints: Mapping[str, np.ndarray] | None = None,
) -> str:
    """The SVG text of ``snapshot``'s segments and points, the lines ``paths`` and the points
    ``markers`` (each (N, 3), world frame, m), projected onto ``plane`` ("xz" or "xy"); in the
    x-y plane also the ``footprints`` (each (5,): centre x, y, half-length, half-width (m), yaw)."""
    if plane not in PLANES:
        raise ValueError(f"unknown plane {plane!r}; choose one of {', '.join(PLANES)}")
    h, v = PLANES[plane]
    series = []
    for name, value in snapshot.items():
        array = np.asarray(value)
        if array.dtype.kind != "f" or array.shape[-1:] != (3,):
            continue
        if array.ndim == 3 and array.shape[1] == 2:  # segments: one sub-path each, NaN between
            gaps = np.full((len(array), 1, 3), np.nan)
            joined = np.concatenate([array, gaps], axis=1).reshape(-1, 3)
            series.append(Series(name, joined[:, h], joined[:, v]))
        elif array.ndim == 2:
            series.append(Series(name, array[:, h], array[:, v], line=False, markers=True))
    for name, path in (paths or {}).items():
        series.append(Series(name, np.asarray(path)[:, h], np.asarray(path)[:, v]))
    for name, points in (markers or {}).items():
        series.append(Series(name, np.asarray(points)[:, h], np.asarray(points)[:, v], line=False, markers=True))
    for name, footprint in (footprints or {}).items() if plane == "xy" else ():
        series.append(Series(name, *outline(footprint)))
    if not series:
        raise ValueError("nothing to draw: no segments, points or paths")
    if plane == "xz":
        xs = np.concatenate([np.asarray(s.x, dtype=float) for s in series])
        low, high = np.nanmin(xs), np.nanmax(xs)
        series.insert(0, Series("ground (z = 0)", [low - 0.1, high + 0.1], [0.0, 0.0], colour="#8c6d31"))
    labels = ("x (m)", "z (m)") if plane == "xz" else ("x (m)", "y (m)")
    return line_plot_svg(series, title, *labels, width=720, height=420, equal_aspect=True)
