"""Replaying a tool motion in a scene: the one loop behind alignment, robot execution, views and checks.

``replay`` resets the scene once (its only draws from ``rng``), steps the tool through the poses and
reads the goal reward; a per-step hook sees the scene after every step (a view takes a snapshot, a
recording logs it).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from toolimit.scenes.base import Scene, SceneParams
from toolimit.tools import ToolPose

#: Called after step t (0-based) with the scene, e.g. to take a snapshot.
StepHook = Callable[[int, Scene], None]


def replay(
    scene: Scene,
    params: SceneParams,
    rng: np.random.Generator,
    poses: ToolPose,
    batch_size: int = 1,
    on_step: StepHook | None = None,
) -> np.ndarray:
    """Reset B instances of ``scene`` with ``params`` (drawing from ``rng``), step the tool through
    ``poses`` ((T, 3) positions m, (T, 3, 3) world-from-tool rotations, world frame), calling
    ``on_step(t, scene)`` after step t; returns the final goal reward (B,).

    Raises InvalidSceneParameters (from ``reset``) when ``params`` cannot make the scene.
    """
    scene.reset(params, rng, batch_size)
    for t, (position, rotation) in enumerate(zip(poses.position, poses.rotation)):
        scene.step(ToolPose(position, rotation))
        if on_step is not None:
            on_step(t, scene)
    return np.asarray(scene.goal_reward(), dtype=float).reshape(batch_size)
