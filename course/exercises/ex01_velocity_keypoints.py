"""Exercise 01: the velocity keypoints of a demonstration (stage ii of the method).

Check your work with ``python grade.py check --exercise ex01`` in the course folder (in the
project's repository: ``python course/grade.py check --exercise ex01``); see README.md. Write the
function yourself: a submission that calls an existing implementation of it (toolimit's, a
dependency's, the course's) scores 0 for the exercise.
"""

from __future__ import annotations

import numpy as np

from toolimit.demos import ToolDemo


def velocity_keypoints(demo: ToolDemo, fraction: float = 0.05) -> np.ndarray:
    """Return the keypoint frames of ``demo``: a 1-D array of sorted, unique ``int`` frame indices.

    The tool speed is ``s = demo.speed()``, shape (T,), in m/s (one value per frame, frames
    0 .. T-1 at ``demo.fps`` Hz). A frame ``t`` is a keypoint when it is

    * the first frame (0) or the last frame (T - 1), always;
    * a local maximum of ``s`` (strictly greater than both neighbours ``s[t-1]`` and ``s[t+1]``)
      whose value is in the top ``fraction`` of all speeds: ``s[t] >= np.quantile(s, 1 - fraction)``;
    * a local minimum of ``s`` (strictly smaller than both neighbours) whose value is in the bottom
      ``fraction``: ``s[t] <= np.quantile(s, fraction)``.

    The end frames are never local extrema (they have only one neighbour); the graded speeds have no
    flat tops (two equal neighbouring values). ``fraction`` is in
    (0, 1]; the paper uses 0.05 (top and bottom 5 %). ``scipy.signal.find_peaks`` may help.

    Args:
        demo: the demonstration (head and handle points in the world frame, metres).
        fraction: share of the speed values counted as "top" and as "bottom".

    Returns:
        (K,) integer array of frame indices, increasing, without repetitions.
    """
    raise NotImplementedError("exercise 01: compute the velocity keypoints")
