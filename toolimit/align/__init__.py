"""Stage (ii): align a scene to a demonstration (keypoints, parameter sampler, search).

``align(demo, tool, world, config, seed, workers)`` returns an :class:`AlignmentResult`; its
candidates are the first K samples (scale, z offset, rolls, scene parameters) under which the
demonstration earns a goal reward. ``write_alignment`` saves it in the project's file formats.
"""

from toolimit.align.config import AlignmentConfig, demo_plane
from toolimit.align.keypoints import velocity_keypoints
from toolimit.align.outputs import write_alignment
from toolimit.align.sampler import (
    AlignmentSample,
    apply_alignment_sample,
    draw_alignment_sample,
    minimum_element_distance,
    sample_element_positions,
)
from toolimit.align.search import AlignmentResult, Candidate, SearchInterrupted, align, prepare_demo

__all__ = [
    "AlignmentConfig",
    "AlignmentResult",
    "AlignmentSample",
    "Candidate",
    "SearchInterrupted",
    "align",
    "apply_alignment_sample",
    "demo_plane",
    "draw_alignment_sample",
    "minimum_element_distance",
    "prepare_demo",
    "sample_element_positions",
    "velocity_keypoints",
    "write_alignment",
]
