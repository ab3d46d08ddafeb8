"""Wrong on purpose: returns the first set drawn, whatever the distances between elements."""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import pdist

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = [
    "test_ex02_elements_respect_min_distance",
    "test_ex02_returns_none_when_impossible",
]


def minimum_element_distance(points: np.ndarray) -> float:
    """Correct: d_th = 0.1 (d_max - d_min), metres, over all pairs of the (T, 3) points."""
    distances = pdist(np.asarray(points, dtype=float))
    return 0.1 * float(distances.max() - distances.min())


def sample_element_positions(
    keypoints: np.ndarray,
    n_elements: int,
    covariance: np.ndarray,
    min_distance: float,
    rng: np.random.Generator,
    weights: np.ndarray | None = None,
    on_ground: np.ndarray | None = None,
    max_attempts: int = 100,
) -> np.ndarray | None:
    """Wrong on purpose: see the module docstring."""
    keypoints = np.asarray(keypoints, dtype=float)
    n_keypoints = len(keypoints)
    weights = np.ones(n_keypoints) if weights is None else np.asarray(weights, dtype=float)
    weights = weights / weights.sum()
    ground = np.zeros(n_elements, bool) if on_ground is None else np.asarray(on_ground, bool)
    for _ in range(max_attempts):
        chosen = rng.choice(n_keypoints, size=n_elements, p=weights)
        positions = keypoints[chosen] + rng.multivariate_normal(np.zeros(3), covariance, size=n_elements)
        positions[ground, 2] = 0.0
        return positions
    return None
