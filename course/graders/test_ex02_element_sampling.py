"""Grader of exercise 02: minimum element distance and Gaussian-mixture element sampling.

Sampling is random, so the sampler is graded by properties over seeded draws (shape, pairwise
distances, ground contact, determinism, mixture statistics), not by equality with the library
``toolimit.align.sampler``; the messages quote the library's figures on the same inputs.
"""

from __future__ import annotations

import numpy as np
import pytest
from grading import case_seeds, check, fail, fmt, fmt_shape
from scipy.spatial.distance import pdist

from toolimit.align.sampler import minimum_element_distance as reference_minimum_distance
from toolimit.align.sampler import sample_element_positions as reference_sample

MODULE = "ex02_element_sampling"
#: Existing implementations of this exercise: a submission calling one of them gets 0 (grading.py).
#: Points of each test group (all its cases share them): 10 for the exercise.
WEIGHTS = {
    "test_ex02_minimum_distance_matches_reference": 2,
    "test_ex02_sample_shape_and_dtype": 1,
    "test_ex02_elements_respect_min_distance": 1.5,
    "test_ex02_on_ground_elements_have_zero_height": 0.5,
    "test_ex02_returns_none_when_impossible": 0.5,
    "test_ex02_same_generator_state_gives_same_positions": 0.5,
    "test_ex02_mixture_statistics": 2,
    "test_ex02_each_element_picks_its_own_keypoint": 1,
    "test_ex02_planar_covariance_keeps_the_plane": 1,
}
#: What each function returns, for the message on a value the checks cannot read.
RETURNS = {
    "minimum_element_distance": "a float, metres",
    "sample_element_positions": "an (n_elements, 3) float array of positions in metres, or None",
}
#: Imported in the student's process before their module (it may start no thread afterwards).
STUDENT_IMPORTS = ["numpy", "scipy.spatial", "toolimit.align"]
FORBIDDEN = ["toolimit.align.sampler"]
#: Seconds a single call may take before the grader assumes an endless loop (conftest.py).
CALL_TIME_LIMIT_S = 20
TOO_SLOW_HINT = ": does the sampler stop after max_attempts?"

#: Three far-apart keypoints (world frame, m), their weights and a full covariance (m^2), used to
#: measure the mixture: each draw is clearly near one keypoint.
FAR_KEYPOINTS = np.array([[0.0, 0.0, 0.5], [3.0, 0.0, 0.8], [0.0, 3.0, 0.3]])
FAR_WEIGHTS = np.array([0.2, 0.3, 0.5])
_L = np.array([[0.2, 0.0, 0.0], [0.05, 0.1, 0.0], [-0.03, 0.02, 0.15]])
COVARIANCE = _L @ _L.T
#: Close keypoints, an isotropic 0.2 m spread and d_th = 0.3 m: the distance rule rejects often.
NEAR_KEYPOINTS = np.array([[0.0, 0.0, 0.5], [0.5, 0.0, 0.5], [0.25, 0.3, 0.5]])
NEAR_COVARIANCE = 0.2**2 * np.eye(3)
NEAR_MIN_DISTANCE = 0.3
ON_GROUND = np.array([True, False, True, False])


def nearest_keypoint(samples: np.ndarray, keypoints: np.ndarray) -> np.ndarray:
    """(N,) index of the keypoint nearest to each sample."""
    return np.argmin(np.linalg.norm(samples[:, None, :] - keypoints[None], axis=2), axis=1)


def draw_singles(sample, n_draws: int, seed: int, weights) -> np.ndarray:
    """(n_draws, 3) positions from n_draws calls with one element each, a generator seeded
    (seed, draw) for each (your function runs in another process: a generator it advances does not
    come back)."""
    draws = [
        sample(FAR_KEYPOINTS, 1, COVARIANCE, 0.0, np.random.default_rng([seed, draw]), weights=weights)
        for draw in range(n_draws)
    ]
    if any(draw is None for draw in draws):
        fail(f"rng seed {seed}: returned None for a single element with min_distance 0 (always possible)")
    return np.concatenate([np.asarray(draw, dtype=float).reshape(1, 3) for draw in draws])


# --- minimum_element_distance ------------------------------------------------------------------
@pytest.mark.parametrize("seed", case_seeds(6))
def test_ex02_minimum_distance_matches_reference(submission, seed):
    rng = np.random.default_rng(seed)
    points = np.cumsum(rng.normal(scale=0.05, size=(int(rng.integers(5, 120)), 3)), axis=0)
    expected = reference_minimum_distance(points)
    got = submission(MODULE).minimum_element_distance(points)
    check(np.ndim(got) == 0, f"seed {seed}, {len(points)} points: expected one number (metres), got {fmt_shape(got)}")
    distances = pdist(points)
    check(
        np.isclose(float(got), expected, rtol=1e-9, atol=1e-12),
        f"seed {seed}, {len(points)} points: expected 0.1 * (d_max - d_min) = {expected:.6f} m "
        f"(d_max {distances.max():.6f} m, d_min {distances.min():.6f} m over all pairs), got {float(got):.6f} m",
    )


# --- sample_element_positions: output and rules ------------------------------------------------
@pytest.mark.parametrize("seed", case_seeds(5, 100))
def test_ex02_sample_shape_and_dtype(submission, seed):
    got = submission(MODULE).sample_element_positions(
        NEAR_KEYPOINTS, 4, NEAR_COVARIANCE, 0.0, np.random.default_rng(seed)
    )
    where = f"rng seed {seed}, 4 elements, min_distance 0"
    check(got is not None, f"{where}: returned None although min_distance is 0 (always possible)")
    positions = np.asarray(got)
    check(positions.shape == (4, 3), f"{where}: expected shape (n_elements, 3) = (4, 3), got {fmt_shape(got)}")
    check(np.issubdtype(positions.dtype, np.floating), f"{where}: expected floats, got {positions.dtype} values")
    check(np.all(np.isfinite(positions)), f"{where}: non-finite positions {fmt(positions)}")


def test_ex02_elements_respect_min_distance(submission):
    violations, placed = [], 0
    for seed in range(40):
        positions = submission(MODULE).sample_element_positions(
            NEAR_KEYPOINTS, 4, NEAR_COVARIANCE, NEAR_MIN_DISTANCE, np.random.default_rng(seed), on_ground=ON_GROUND
        )
        if positions is None:
            continue
        placed += 1
        closest = pdist(np.asarray(positions, dtype=float)).min()
        if closest < NEAR_MIN_DISTANCE - 1e-12:
            violations.append(f"seed {seed}: two elements {closest:.3f} m apart")
    check(
        not violations,
        lambda: (
            f"every pair must be at least min_distance = {NEAR_MIN_DISTANCE} m apart (measured after z := 0 "
            "on the ground); redraw the whole set otherwise:\n  " + "\n  ".join(violations[:5])
        ),
    )
    library = sum(
        reference_sample(
            NEAR_KEYPOINTS, 4, NEAR_COVARIANCE, NEAR_MIN_DISTANCE, np.random.default_rng(s), on_ground=ON_GROUND
        )
        is not None
        for s in range(40)
    )
    check(
        placed >= 0.8 * library,
        f"rng seeds 0 to 39, 4 elements, min_distance {NEAR_MIN_DISTANCE} m: you returned None in {40 - placed} "
        f"of 40 draws, the library in {40 - library}: retry up to max_attempts sets before giving up",
    )


def test_ex02_on_ground_elements_have_zero_height(submission):
    for seed in range(10):
        positions = submission(MODULE).sample_element_positions(
            NEAR_KEYPOINTS, 4, NEAR_COVARIANCE, 0.0, np.random.default_rng(seed), on_ground=ON_GROUND
        )
        where = f"rng seed {seed}, on_ground {fmt(ON_GROUND)}"
        check(positions is not None, f"{where}: returned None although min_distance is 0 (always possible)")
        positions = np.asarray(positions, dtype=float)
        check(
            np.all(positions[ON_GROUND, 2] == 0.0),
            f"{where}: elements {fmt(np.flatnonzero(ON_GROUND))} are on the ground, their z must be "
            f"exactly 0; got z = {fmt(positions[ON_GROUND, 2])}",
        )
        check(
            np.all(positions[~ON_GROUND, 2] != 0.0),
            f"{where}: only elements with on_ground True go to z = 0; elements "
            f"{fmt(np.flatnonzero(~ON_GROUND))} got z = {fmt(positions[~ON_GROUND, 2])}",
        )
        spread = np.linalg.norm(positions[ON_GROUND, :2] - NEAR_KEYPOINTS[:, :2].mean(axis=0), axis=1)
        check(
            np.all(spread < 2.0),
            f"{where}: ground elements must keep their drawn x and y, got positions {fmt(positions)} m",
        )


def test_ex02_returns_none_when_impossible(submission):
    tiny = 1e-6 * np.eye(3)
    positions = submission(MODULE).sample_element_positions(
        np.array([[0.0, 0.0, 1.0]]), 3, tiny, 1.0, np.random.default_rng(0), max_attempts=10
    )
    check(
        positions is None,
        lambda: (
            "three elements 1 m apart around one keypoint (0, 0, 1) with a 1 mm spread cannot be placed: "
            f"expected None after max_attempts = 10, got {fmt(positions)}"
        ),
    )


def test_ex02_same_generator_state_gives_same_positions(submission):
    sample = submission(MODULE).sample_element_positions
    results = []
    for global_seed in (1, 2):
        np.random.seed(global_seed)  # a solution using np.random.* instead of rng changes here
        results.append(sample(FAR_KEYPOINTS, 3, COVARIANCE, 0.1, np.random.default_rng(7), on_ground=ON_GROUND[:3]))
    first, second = results
    check(first is not None and second is not None, "rng seed 7, 3 elements: returned None for an easy draw")
    check(
        np.array_equal(first, second),
        lambda: (
            f"the same rng (seed 7) gave different positions, {fmt(first)} then {fmt(second)}: "
            "draw only from `rng`, never from np.random.*"
        ),
    )
    other = sample(FAR_KEYPOINTS, 3, COVARIANCE, 0.1, np.random.default_rng(8), on_ground=ON_GROUND[:3])
    check(
        not np.array_equal(first, other),
        lambda: f"rng seeds 7 and 8 gave the same positions {fmt(first)}: use `rng` to draw",
    )


# --- sample_element_positions: the mixture -----------------------------------------------------
def mixture_report(samples: np.ndarray) -> str:
    component = nearest_keypoint(samples, FAR_KEYPOINTS)
    fractions = np.bincount(component, minlength=len(FAR_KEYPOINTS)) / len(samples)
    offsets = samples - FAR_KEYPOINTS[component]
    return f"share per keypoint {fmt(fractions, 3)}, offset mean {fmt(offsets.mean(0), 3)} m"


@pytest.mark.parametrize("weights", [FAR_WEIGHTS, 10 * FAR_WEIGHTS, None], ids=["weights", "unnormalised", "uniform"])
def test_ex02_mixture_statistics(submission, weights):
    n_draws = 1000
    samples = draw_singles(submission(MODULE).sample_element_positions, n_draws, 11, weights)
    expected_weights = np.full(3, 1 / 3) if weights is None else FAR_WEIGHTS

    def figures() -> str:  # only computed for a failure message
        library = draw_singles(reference_sample, n_draws, 11, weights)
        return f"\n  yours:   {mixture_report(samples)}\n  library: {mixture_report(library)}"

    distance = np.min(np.linalg.norm(samples[:, None, :] - FAR_KEYPOINTS[None], axis=2), axis=1)
    far = np.flatnonzero(distance > 6 * np.sqrt(np.linalg.eigvalsh(COVARIANCE).max()))
    check(
        not far.size,
        lambda: (
            f"{far.size} draws are far from every keypoint (e.g. {fmt(samples[far[0]], 3)} m): each element is "
            f"drawn around ONE keypoint k_i chosen with probability w_i, not around their mean{figures()}"
        ),
    )
    component = nearest_keypoint(samples, FAR_KEYPOINTS)
    fractions = np.bincount(component, minlength=3) / n_draws
    tolerance = 5 * np.sqrt(expected_weights * (1 - expected_weights) / n_draws)
    check(
        np.all(np.abs(fractions - expected_weights) <= tolerance),
        lambda: (
            f"keypoint i must be chosen with probability w_i = {fmt(expected_weights, 3)} "
            f"(normalised weights; equal when None), your draws chose {fmt(fractions, 3)}{figures()}"
        ),
    )
    offsets = samples - FAR_KEYPOINTS[component]
    mean_tolerance = 5 * np.sqrt(np.diag(COVARIANCE) / n_draws)
    check(
        np.all(np.abs(offsets.mean(axis=0)) <= mean_tolerance),
        lambda: f"draws must be centred on their keypoint, mean offset {fmt(offsets.mean(0), 4)} m{figures()}",
    )
    covariance = np.cov(offsets.T)
    check(
        np.allclose(covariance, COVARIANCE, atol=0.2 * np.diag(COVARIANCE).max()),
        lambda: (
            "offsets from the keypoint must have covariance Sigma (m^2; a covariance, not standard deviations): "
            f"expected {fmt(COVARIANCE, 4)}, got {fmt(covariance, 4)}{figures()}"
        ),
    )


def test_ex02_each_element_picks_its_own_keypoint(submission):
    positions = submission(MODULE).sample_element_positions(
        FAR_KEYPOINTS, 300, COVARIANCE, 0.0, np.random.default_rng(3), weights=FAR_WEIGHTS
    )
    check(positions is not None, "rng seed 3, 300 elements: returned None although min_distance is 0 (always possible)")
    fractions = np.bincount(nearest_keypoint(np.asarray(positions, dtype=float), FAR_KEYPOINTS), minlength=3) / 300
    tolerance = 5 * np.sqrt(FAR_WEIGHTS * (1 - FAR_WEIGHTS) / 300)
    check(
        np.all(np.abs(fractions - FAR_WEIGHTS) <= tolerance),
        f"rng seed 3: within one call, each element chooses its keypoint independently (weights "
        f"{fmt(FAR_WEIGHTS)}); your 300 elements chose the keypoints in shares {fmt(fractions, 3)}",
    )


def test_ex02_planar_covariance_keeps_the_plane(submission):
    planar = np.diag([0.04, 0.0, 0.04])  # x-z world: no spread across the plane (y)
    keypoints = FAR_KEYPOINTS * np.array([1.0, 0.0, 1.0])
    positions = submission(MODULE).sample_element_positions(keypoints, 5, planar, 0.05, np.random.default_rng(5))
    where = f"rng seed 5, 5 elements, Sigma = diag{fmt(np.diag(planar))} m^2"
    check(positions is not None, f"{where}: returned None for an easy planar draw")
    positions = np.asarray(positions, dtype=float)
    check(
        np.allclose(positions[:, 1], 0.0, atol=1e-9),
        f"{where}: with zero variance along y (a singular Sigma), y must stay at the keypoints' y = 0; "
        f"got y = {fmt(positions[:, 1])}",
    )
    check(np.ptp(positions[:, 0]) > 0, f"{where}: the draws must still spread along x, got x = {fmt(positions[:, 0])}")
