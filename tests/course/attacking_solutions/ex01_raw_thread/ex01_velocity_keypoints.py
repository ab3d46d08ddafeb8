"""Attack: call the library's answer from a raw thread (the profiler of the guard is not installed
in threads started by `_thread`), reaching `_thread` and the library through built names."""

import importlib
import time

import numpy as np


def velocity_keypoints(demo, fraction=0.05):
    threads = importlib.import_module("_" + "thread")
    library = importlib.import_module("toolimit.align." + "keypoints")
    answer = []
    start = getattr(threads, "start_new_" + "thread")
    start(lambda: answer.append(getattr(library, "velocity_" + "keypoints")(demo, fraction)), ())
    for _ in range(200):
        if answer:
            return answer[0]
        time.sleep(0.01)
    return np.array([0], dtype=int)
