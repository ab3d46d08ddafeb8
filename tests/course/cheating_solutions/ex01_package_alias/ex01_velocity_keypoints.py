"""Cheats: reaches the library's function through the package's re-export and an alias."""

import toolimit.align as alignment
from toolimit.demos import ToolDemo


def velocity_keypoints(demo: ToolDemo, fraction: float = 0.05):
    return alignment.velocity_keypoints(demo, fraction)
