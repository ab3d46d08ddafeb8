"""Wrong on purpose: compares the maxima with the bottom quantile and the minima with the top one."""

import numpy as np

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = [
    "test_ex01_keypoints_match_reference",
]


def velocity_keypoints(demo, fraction=0.05):
    speed = demo.speed()
    before, here, after = speed[:-2], speed[1:-1], speed[2:]
    is_max = (here > before) & (here > after) & (here >= np.quantile(speed, fraction))
    is_min = (here < before) & (here < after) & (here <= np.quantile(speed, 1.0 - fraction))
    inner = 1 + np.flatnonzero(is_max | is_min)
    return np.unique(np.concatenate([[0, demo.n_frames - 1], inner])).astype(int)
