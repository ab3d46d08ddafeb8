"""Wrong: counts frames from 1, so the last keypoint is frame T (one past the end)."""

import numpy as np

CAUGHT_BY = [
    "test_ex01_output_is_sorted_unique_int_frames",
    "test_ex01_first_and_last_frame",
    "test_ex01_keypoints_match",
]


def velocity_keypoints(demo, fraction=0.05):
    speed = demo.speed()
    before, here, after = speed[:-2], speed[1:-1], speed[2:]
    is_max = (here > before) & (here > after) & (here >= np.quantile(speed, 1.0 - fraction))
    is_min = (here < before) & (here < after) & (here <= np.quantile(speed, fraction))
    inner = 1 + np.flatnonzero(is_max | is_min)
    return np.unique(np.concatenate([[0, demo.n_frames - 1], inner])).astype(int) + 1
