"""Velocity keypoints on hand-made speed profiles and on a real motion with known extrema."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from toolimit.align.keypoints import velocity_keypoints
from toolimit.demos import ToolDemo


@dataclass(frozen=True)
class ProfileDemo(ToolDemo):
    """A demo whose speed is a given profile (m/s), to test the keypoint rule alone."""

    profile: np.ndarray = None  # type: ignore[assignment]

    def speed(self) -> np.ndarray:
        return np.asarray(self.profile, dtype=float)


def profile_demo(speed: list[float]) -> ProfileDemo:
    head = np.zeros((len(speed), 3))
    return ProfileDemo(head, head + [0.0, 0.0, 0.4], 24.0, "spade", profile=np.array(speed))


def test_ends_plus_top_maximum_and_bottom_minimum():
    #        0    1    2    3    4    5    6    7    8    9    10   11   12   13
    speed = [0.5, 0.6, 3.0, 0.6, 0.5, 0.4, 0.3, 0.05, 0.3, 0.4, 1.0, 0.4, 0.35, 0.36]
    # With 14 values, the 0.05 quantiles are close to the extremes: only the peak 3.0 and the
    # dip 0.05 qualify; the lesser peak 1.0 (frame 10) and the end frames' values do not matter.
    np.testing.assert_array_equal(velocity_keypoints(profile_demo(speed), 0.05), [0, 2, 7, 13])


def test_larger_fraction_admits_lesser_extrema():
    speed = [0.5, 0.6, 3.0, 0.6, 0.5, 0.4, 0.3, 0.05, 0.3, 0.4, 1.0, 0.4, 0.35, 0.36]
    # fraction 0.3: top threshold = 0.7 quantile (0.57), bottom = 0.3 quantile (0.36):
    # peak 1.0 at frame 10 joins, and the dip 0.35 at frame 12.
    np.testing.assert_array_equal(velocity_keypoints(profile_demo(speed), 0.3), [0, 2, 7, 10, 12, 13])


def test_flat_top_and_monotone_profile_give_only_the_ends():
    assert velocity_keypoints(profile_demo([1.0, 2.0, 3.0, 3.0, 2.0, 1.0, 0.5, 0.4, 0.3, 0.2])).tolist() == [0, 9]
    assert velocity_keypoints(profile_demo(list(np.linspace(0.1, 2.0, 30)))).tolist() == [0, 29]


def test_sorted_unique_int_and_bad_fraction():
    frames = velocity_keypoints(profile_demo([1, 3, 1, 3, 1, 0.1, 1, 3, 1, 2, 1, 3]), 0.5)
    assert frames.dtype.kind == "i" and np.all(np.diff(frames) > 0)
    with pytest.raises(ValueError, match="fraction"):
        velocity_keypoints(profile_demo([1.0] * 12), 0.0)


def test_cosine_speed_motion_has_keypoints_at_its_extrema():
    # Head speed 1 + 0.9 cos(2 pi t) m/s for 4 s at 24 fps (exact positions, no rotation):
    # maxima at whole seconds (frames 24, 48, 72), minima at half seconds (12, 36, 60, 84).
    fps, t = 24.0, np.arange(97) / 24.0
    x = t + 0.9 * np.sin(2 * np.pi * t) / (2 * np.pi)
    head = np.stack([x, np.zeros_like(t), np.full_like(t, 0.3)], axis=1)
    demo = ToolDemo(head, head + [0.0, 0.0, 0.4], fps, "spade")
    np.testing.assert_array_equal(velocity_keypoints(demo), [0, 12, 24, 36, 48, 60, 72, 84, 96])
