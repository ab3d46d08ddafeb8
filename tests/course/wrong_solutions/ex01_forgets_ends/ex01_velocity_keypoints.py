"""Wrong on purpose: forgets that the first and last frames are always keypoints."""

import numpy as np

#: The grader tests (name prefixes) that must fail on this file.
CAUGHT_BY = [
    "test_ex01_first_and_last_frame_are_keypoints",
    "test_ex01_keypoints_match_reference",
]


def velocity_keypoints(demo, fraction=0.05):
    speed = demo.speed()
    before, here, after = speed[:-2], speed[1:-1], speed[2:]
    is_max = (here > before) & (here > after) & (here >= np.quantile(speed, 1.0 - fraction))
    is_min = (here < before) & (here < after) & (here <= np.quantile(speed, fraction))
    return 1 + np.flatnonzero(is_max | is_min)
