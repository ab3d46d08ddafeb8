"""Reference solution of exercise 02 (instructors): Gaussian-mixture element sampling, written out."""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import pdist


def minimum_element_distance(points: np.ndarray) -> float:
    """d_th = 0.1 (d_max - d_min), metres, over all pairs of the (T, 3) points."""
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
    """(n_elements, 3) positions x_j ~ sum_i w_i N(k_i, Sigma), pairwise >= min_distance, or None."""
    keypoints = np.asarray(keypoints, dtype=float)
    n_keypoints = len(keypoints)
    weights = np.ones(n_keypoints) if weights is None else np.asarray(weights, dtype=float)
    weights = weights / weights.sum()
    ground = np.zeros(n_elements, bool) if on_ground is None else np.asarray(on_ground, bool)
    for _ in range(max_attempts):
        chosen = rng.choice(n_keypoints, size=n_elements, p=weights)
        positions = keypoints[chosen] + rng.multivariate_normal(np.zeros(3), covariance, size=n_elements)
        positions[ground, 2] = 0.0
        if n_elements == 1 or pdist(positions).min() >= min_distance:
            return positions
    return None
