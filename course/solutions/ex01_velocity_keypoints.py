"""Reference solution of exercise 01 (instructors): velocity keypoints, written out plainly."""

from __future__ import annotations

import numpy as np

from toolimit.demos import ToolDemo


def velocity_keypoints(demo: ToolDemo, fraction: float = 0.05) -> np.ndarray:
    """Sorted unique int frames: both ends, top-``fraction`` local maxima and bottom-``fraction``
    local minima of the tool speed (m/s)."""
    speed = demo.speed()
    before, here, after = speed[:-2], speed[1:-1], speed[2:]
    is_max = (here > before) & (here > after) & (here >= np.quantile(speed, 1.0 - fraction))
    is_min = (here < before) & (here < after) & (here <= np.quantile(speed, fraction))
    inner = 1 + np.flatnonzero(is_max | is_min)
    return np.unique(np.concatenate([[0, demo.n_frames - 1], inner])).astype(int)
