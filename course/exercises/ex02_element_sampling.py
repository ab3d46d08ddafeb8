"""Exercise 02: placing scene elements around the keypoints (stage ii of the method).

Check your work with ``python grade.py check --exercise ex02`` in the course folder (in the
project's repository: ``python course/grade.py check --exercise ex02``); see README.md. Write the
function yourself: a submission that calls an existing implementation of it (toolimit's, a
dependency's, the course's) scores 0 for the exercise.
"""

from __future__ import annotations

import numpy as np


def minimum_element_distance(points: np.ndarray) -> float:
    """Return d_th = 0.1 * (d_max - d_min), in metres, as a Python float.

    ``points`` is a (T, 3) array of trajectory points (the tool head over the demonstration), world
    frame, metres, T >= 2. d_max and d_min are the largest and the smallest Euclidean distance
    between two *different* frames, over all pairs (i < j), not only consecutive frames.
    ``scipy.spatial.distance.pdist`` may help.
    """
    raise NotImplementedError("exercise 02: compute the minimum element distance")


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
    """Draw ``n_elements`` scene element positions from a Gaussian mixture around the keypoints.

    Each element j independently: pick a keypoint i with probability w_i, then draw
    x_j ~ N(k_i, Sigma), i.e. x_j ~ sum_i w_i N(k_i, Sigma). Elements with ``on_ground[j]`` True
    stand on the ground: set their z to exactly 0 (the other coordinates keep their draw).
    The whole set is valid when every pair of elements is at least ``min_distance`` apart
    (Euclidean, after zeroing z); otherwise draw the whole set again. After ``max_attempts``
    invalid sets, give up and return None.

    Use only ``rng`` for randomness (never ``np.random.*`` functions), so the same generator state
    gives the same positions. ``Sigma`` may be singular (a planar world has zero variance across
    its plane): ``rng.multivariate_normal`` handles that with its default method.

    Args:
        keypoints: (K, 3) mixture means k_i (head positions at the keypoint frames), world frame, m.
        n_elements: number of positions to draw (>= 1).
        covariance: (3, 3) covariance Sigma of every mixture component, m^2.
        min_distance: d_th, metres.
        rng: the random generator to draw from.
        weights: (K,) non-negative mixture weights, not necessarily summing to 1 (normalise them);
            None means equal weights 1/K.
        on_ground: (n_elements,) booleans; None means no element is on the ground.
        max_attempts: number of sets drawn before giving up.

    Returns:
        (n_elements, 3) float array of positions (world frame, metres), or None.
    """
    raise NotImplementedError("exercise 02: sample the element positions")
