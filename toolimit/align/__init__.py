"""Stage (ii): align a scene to a demonstration (keypoints, parameter sampler, search)."""
