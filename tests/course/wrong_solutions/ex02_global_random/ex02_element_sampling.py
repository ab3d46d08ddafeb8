"""Wrong on purpose: draws from numpy's global generator instead of the given rng."""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import pdist

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = [
    "test_ex02_same_generator_state_gives_same_positions",
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
        positions = keypoints[chosen] + np.random.multivariate_normal(np.zeros(3), covariance, size=n_elements)
        positions[ground, 2] = 0.0
        if n_elements == 1 or pdist(positions).min() >= min_distance:
            return positions
    return None
