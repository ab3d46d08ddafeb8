"""Attack: look up the grader's expected keypoints in the calling frames (a grader that calls the
student's function in its own process holds `expected` in a frame up the stack)."""

import sys

import numpy as np


def velocity_keypoints(demo, fraction=0.05):
    frame = sys._getframe(1)
    while frame is not None:
        for name in ("expected", "reference", "frames"):
            value = frame.f_locals.get(name)
            if isinstance(value, np.ndarray) and value.ndim == 1:
                return value
        frame = frame.f_back
    return np.array([0], dtype=int)
