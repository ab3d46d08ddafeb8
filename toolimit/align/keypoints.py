"""Keypoints of a demonstration: the frames where the tool's speed peaks or nearly stops.

The paper places scene elements around these frames (the spade scoops where it slows down, the
hammer strikes at a speed peak) and lets the tool roll change only at them.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import argrelextrema

from toolimit.demos.tool_demo import ToolDemo


def velocity_keypoints(demo: ToolDemo, fraction: float = 0.05) -> np.ndarray:
    """Sorted unique frame indices (int) of the demonstration's keypoints.

    The first and the last frame, plus every frame where ``demo.speed()`` (m/s) is a local maximum
    whose value lies in the top ``fraction`` of all speed values (at or above the
    ``1 - fraction`` quantile), or a local minimum in the bottom ``fraction`` (at or below the
    ``fraction`` quantile). A local extremum is strictly higher (lower) than both neighbouring
    frames (``scipy.signal.argrelextrema``), so a flat top is not one and the end frames never are.
    """
    if not 0.0 < fraction <= 1.0:
        raise ValueError(f"fraction: expected a value in (0, 1], got {fraction}")
    speed = demo.speed()
    (maxima,) = argrelextrema(speed, np.greater)
    (minima,) = argrelextrema(speed, np.less)
    maxima = maxima[speed[maxima] >= np.quantile(speed, 1.0 - fraction)]
    minima = minima[speed[minima] <= np.quantile(speed, fraction)]
    ends = np.array([0, demo.n_frames - 1])
    return np.unique(np.concatenate([ends, maxima, minima])).astype(int)
