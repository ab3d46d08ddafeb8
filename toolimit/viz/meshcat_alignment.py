"""The best alignment candidate's replay as a self-contained meshcat HTML page (3D worlds).

What ``toolimit align --html FILE`` writes: the scene built from the best candidate's parameters,
replayed with its aligned tool motion exactly as the search did (the candidate's generator
``default_rng([seed, index])``, advanced past the sample draw), the tool drawn from
:mod:`toolimit.scenes.spatial.tool_geometry`, and the aligned tool poses at the demonstration's
keypoints as small triads.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from toolimit.align.search import AlignmentResult
from toolimit.scenes.base import Scene
from toolimit.scenes.registry import make_scene
from toolimit.tools import ToolPose
from toolimit.viz.meshcat_views import replay_scene, replay_to_html


def save_alignment_html(result: AlignmentResult, path: str | os.PathLike[str], scene: Scene | None = None) -> Path:
    """Write the best candidate's replay of ``result`` to ``path`` (HTML, atomically).

    ``scene`` replays it (default: a new scene from the registry). Raises ValueError when the
    search found no candidate or the world is not 3D (meshcat views draw the 3D worlds).
    """
    if result.world != "3d":
        raise ValueError(f"meshcat views draw the 3D worlds; this alignment is in the {result.world!r} world")
    best = result.best
    if best is None:
        raise ValueError(f"the alignment found no candidate in {result.samples_tried} samples: nothing to show")
    _, _, poses = result.aligned_motion(best)
    scene = scene or make_scene(result.tool, result.world)
    rng = result.replay_generator(best, scene.parameters)
    frames = replay_scene(scene, poses, best.sample.params, rng)
    keypoints = np.asarray(result.keypoints)
    targets = ToolPose(np.asarray(poses.position)[keypoints], np.asarray(poses.rotation)[keypoints])
    return replay_to_html(path, frames, result.tool, targets=targets, fps=1.0 / scene.control_dt)
