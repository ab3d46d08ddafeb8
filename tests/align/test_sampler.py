"""Element sampler (mixture, minimum distance, ground) and applying a sample to a demonstration."""

from __future__ import annotations

import numpy as np
import pytest
from align_fake_scene import FakeTargetScene, make_demo
from scipy.spatial.distance import pdist

from toolimit.align.config import AlignmentConfig
from toolimit.align.keypoints import velocity_keypoints
from toolimit.align.sampler import (
    AlignmentSample,
    apply_alignment_sample,
    draw_alignment_sample,
    minimum_element_distance,
    roll_per_frame,
    sample_element_positions,
)
from toolimit.tools import roll_of


def test_minimum_element_distance_is_a_tenth_of_the_distance_range():
    points = np.array([[0.0, 0, 0], [1.0, 0, 0], [3.0, 0, 0]])  # pairwise distances 1, 2, 3
    assert minimum_element_distance(points) == pytest.approx(0.2)
    with pytest.raises(ValueError, match="points"):
        minimum_element_distance(np.zeros((5, 2)))


def test_min_distance_respected_and_ground_elements_at_zero():
    keypoints = np.array([[0.0, 0.0, 0.3], [0.5, 0.0, 0.1], [1.0, 0.2, 0.4]])
    on_ground = np.array([True, False, True, False])
    for seed in range(50):
        rng = np.random.default_rng(seed)
        points = sample_element_positions(keypoints, 4, 0.04 * np.eye(3), 0.15, rng, on_ground=on_ground)
        assert points is not None and points.shape == (4, 3)
        assert pdist(points).min() >= 0.15
        assert np.all(points[on_ground, 2] == 0.0)
        assert np.all(points[~on_ground, 2] != 0.0)


def test_mixture_weights_and_component_covariance():
    keypoints = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]])
    covariance = np.diag([0.04, 0.01, 0.09])
    rng = np.random.default_rng(7)
    draws = np.array(
        [sample_element_positions(keypoints, 1, covariance, 0.0, rng, weights=np.array([1.0, 3.0]))[0] for _ in range(4000)]
    )
    near_second = draws[:, 0] > 5.0
    assert near_second.mean() == pytest.approx(0.75, abs=0.03)
    centred = np.where(near_second[:, None], draws - keypoints[1], draws - keypoints[0])
    np.testing.assert_allclose(centred.mean(axis=0), 0.0, atol=0.02)
    np.testing.assert_allclose(np.cov(centred.T), covariance, atol=0.008)


def test_none_when_min_distance_is_impossible():
    rng = np.random.default_rng(0)
    tight = 1e-8 * np.eye(3)
    assert sample_element_positions(np.array([[0.0, 0, 0]]), 3, tight, 1.0, rng, max_attempts=20) is None
    # A single element never conflicts.
    assert sample_element_positions(np.array([[0.0, 0, 0]]), 1, tight, 1.0, rng) is not None


def test_sampler_is_reproducible_with_the_same_seed():
    keypoints = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    a = sample_element_positions(keypoints, 2, 0.01 * np.eye(3), 0.1, np.random.default_rng(3))
    b = sample_element_positions(keypoints, 2, 0.01 * np.eye(3), 0.1, np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)


def test_roll_is_constant_between_keypoints():
    keypoints = np.array([0, 4, 9, 14])
    roll = roll_per_frame(15, keypoints, np.array([0.1, -2.0, 3.0]))
    np.testing.assert_array_equal(roll[:4], 0.1)
    np.testing.assert_array_equal(roll[4:9], -2.0)
    np.testing.assert_array_equal(roll[9:], 3.0)
    with pytest.raises(ValueError, match="rolls"):
        roll_per_frame(15, keypoints, np.zeros(4))


def test_applied_sample_keeps_tool_length_scales_heights_and_carries_the_roll():
    demo = make_demo()
    keypoints = velocity_keypoints(demo)
    rolls = np.linspace(-3.0, 3.0, len(keypoints) - 1)
    sample = AlignmentSample(scale=0.5, z_offset=0.07, rolls=rolls, params={})
    aligned, roll, poses = apply_alignment_sample(demo, keypoints, sample)
    np.testing.assert_allclose(aligned.lengths, demo.lengths, rtol=1e-9)
    # Scaled about a ground point: heights halve, then the offset lifts them.
    np.testing.assert_allclose(aligned.head[:, 2], 0.5 * demo.head[:, 2] + 0.07, atol=1e-12)
    np.testing.assert_allclose(np.ptp(aligned.head[:, 0]), 0.5 * np.ptp(demo.head[:, 0]), rtol=1e-9)
    np.testing.assert_allclose(poses.position, aligned.head)
    np.testing.assert_allclose(poses.rotation[:, :, 2], aligned.axis, atol=1e-9)
    np.testing.assert_allclose(roll_of(poses.rotation), roll, atol=1e-9)
    changes = np.flatnonzero(np.diff(roll)) + 1
    assert set(changes.tolist()) <= set(keypoints.tolist())


def test_drawn_sample_places_ground_elements_near_the_transformed_keypoints():
    demo = make_demo()
    keypoints = velocity_keypoints(demo)
    scene = FakeTargetScene()
    config = AlignmentConfig(element_std=0.05)
    covariance = config.element_covariance("xz")
    for seed in range(30):
        sample = draw_alignment_sample(demo, keypoints, scene.parameters, config, covariance, 0.05, np.random.default_rng(seed))
        assert sample is not None and sample.scale in config.scales
        assert list(sample.params) == ["target", "radius"]
        target = sample.params["target"]
        assert target[1] == 0.0 and target[2] == 0.0  # no spread across the plane, on the ground
        head = demo.scaled(sample.scale, about=np.r_[demo.head.mean(0)[:2], 0.0]).head[keypoints]
        assert np.min(np.abs(head[:, 0] - target[0])) < 4 * 0.05
        assert 0.0 <= sample.params["radius"] <= 0.1
        assert sample.rolls.shape == (len(keypoints) - 1,) and np.all(np.abs(sample.rolls) <= np.pi)


def test_planar_rolls_face_one_side_of_the_plane_and_use_the_same_draws():
    """In the vertical x-z plane the whole motion takes roll 0 or pi (the blade's x stays in the
    plane, on one face); the generator is used exactly as in 3D, so every other value is unchanged."""
    from toolimit.align.config import AlignmentConfig
    from toolimit.align.sampler import apply_alignment_sample, draw_alignment_sample
    from toolimit.demos import ToolDemo

    t = np.linspace(0.0, 1.0, 48)
    head = np.column_stack([t, np.zeros_like(t), 0.1 + 0.3 * np.sin(np.pi * t) ** 2])
    demo = ToolDemo(head=head, handle=head + [0.1, 0.0, 0.38], fps=24, tool="spade")
    keypoints = np.array([0, 12, 24, 36, 47])
    config = AlignmentConfig()
    for seed in range(20):
        draws = [
            draw_alignment_sample(demo, keypoints, (), config, np.eye(3) * 0.01, 0.05, np.random.default_rng(seed), plane=plane)
            for plane in (None, "xz")
        ]
        free, planar = draws
        assert set(np.round(planar.rolls, 12)) <= {0.0, round(np.pi, 12)}
        assert np.all(planar.rolls == (0.0 if abs(free.rolls[0]) < np.pi / 2 else np.pi))
        assert (planar.scale, planar.z_offset) == (free.scale, free.z_offset)
        _, _, poses = apply_alignment_sample(demo, keypoints, planar)
        assert np.allclose(poses.rotation[:, 1, 0], 0.0)  # tool x has no component along world y
