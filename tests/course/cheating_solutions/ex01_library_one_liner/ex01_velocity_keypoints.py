"""Cheats: the one-line submission of the trial, the library's own function."""

from toolimit.align.keypoints import velocity_keypoints  # noqa: F401
