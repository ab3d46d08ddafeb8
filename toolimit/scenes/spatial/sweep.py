"""A hand-made scythe motion for the 3D scythe scene (tests, LfD baseline).

A motion generator, kept apart from the scene it is made for: it reads the grass patch's
parameters and the scythe's geometry, and returns tool poses any scene replay can follow. The
authors' rule (:mod:`toolimit.scenes.scythe_cut`) cuts with the blade's side towards the handle,
moving towards the handle, with the snath within 30 degrees of horizontal. So the scythe is held
with the blade (tool x) level along world +x and the snath (tool z, towards the handle) pointing
along world -y, raised ``SNATH_ELEVATION`` (20 degrees: the handle end 0.23 m above the blade,
within a robot's reach), and pulled towards -y across the patch.
"""

from __future__ import annotations

import numpy as np

from toolimit.demos.tool_demo import ToolDemo
from toolimit.scenes.base import CONTROL_FPS, SceneParams
from toolimit.scenes.scythe_cut import scythe_cut_rule
from toolimit.tools import ToolPose, hold_last, tool_spec

#: World-from-tool rotation of the level scythe: tool x = world x, tool y = world z, tool z = -y.
LEVEL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
#: How far the scripted pull raises the snath above horizontal (rad), turning about the blade.
SNATH_ELEVATION = np.deg2rad(20.0)
#: Seconds the demonstrator holds the scythe still before the pulls (:func:`pull_demonstration`).
LEAD_IN_S = 0.75


def raised(elevation: float) -> np.ndarray:
    """World-from-tool rotation of the scythe with its snath raised ``elevation`` rad from
    :data:`LEVEL` (about the blade, world x: the handle end goes up)."""
    c, s = np.cos(elevation), np.sin(elevation)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]) @ LEVEL


def pull(
    edge_centre: np.ndarray, start_y: float, end_y: float, speed: float, dt: float, elevation: float = 0.0
) -> ToolPose:
    """Poses every ``dt`` s of the scythe (snath raised ``elevation`` rad, :func:`raised`) whose
    cutting edge's centre moves along world y from ``start_y`` to ``end_y`` (m) at ``speed`` (m/s),
    at x and height of ``edge_centre`` (3,) m."""
    rotation = raised(elevation)
    edge = scythe_cut_rule(0.005).edge  # (2, 3) tool frame
    head_offset = rotation @ edge.mean(axis=0)  # edge centre relative to the head point, world, m
    steps = max(1, int(np.ceil(abs(end_y - start_y) / (speed * dt))))
    y = np.linspace(start_y, end_y, steps + 1)
    centres = np.column_stack([np.full(steps + 1, edge_centre[0]), y, np.full(steps + 1, edge_centre[2])])
    return ToolPose(centres - head_offset, np.repeat(rotation[None], steps + 1, axis=0))


def scripted_sweep(params: SceneParams, fps: float = CONTROL_FPS, speed: float = 1.5, height: float = 0.05) -> ToolPose:
    """Two pulls across the patch at ``grass_position`` that cut every stalk within the first
    second: the blade's edge level, ``height`` m above the ground, centred 5 cm left then 5 cm
    right of the patch centre (the 0.35 m edge reaches 1 cm beyond its ends: one pull may miss a
    stalk at the patch's end), pulled at ``speed`` m/s (the rule's approach needs more than 1 m/s)
    from 0.1 m beyond the patch's far side (+y) to 0.1 m beyond its near side, pushed back in
    between (pushing cuts nothing), the snath raised :data:`SNATH_ELEVATION`, then held 0.25 s.
    Returns (T, 3) head positions and (T, 3, 3) rotations (world frame) at ``fps``."""
    patch = np.asarray(params["grass_position"], dtype=float)
    dt = 1.0 / fps
    far, near = patch[1] + 0.15, patch[1] - 0.15
    parts = []
    for shift in (-0.05, 0.05):
        centre = np.array([patch[0] + shift, 0.0, height])
        parts += [
            pull(centre, far, near, speed, dt, SNATH_ELEVATION),
            pull(centre, near, far, speed, dt, SNATH_ELEVATION),
        ]
    motion = ToolPose(
        np.concatenate([p.position for p in parts[:-1]]), np.concatenate([p.rotation for p in parts[:-1]])
    )
    return hold_last(motion, int(np.ceil(0.25 * fps)))


def pull_demonstration(params: SceneParams, fps: float = CONTROL_FPS) -> ToolDemo:
    """The scripted pulls for the patch at ``grass_position`` as a demonstration, after
    :data:`LEAD_IN_S` still: head and handle-end points (the simulated scythe's length), world
    frame, m, at ``fps``. The shipped scythe demonstrations sweep around the body with the snath
    40-55 degrees up, which the authors' cut rule never rewards (README); this one it does."""
    motion = scripted_sweep(params, fps)
    index = np.concatenate([np.zeros(int(round(LEAD_IN_S * fps)), dtype=int), np.arange(len(motion.position))])
    head = motion.position[index]
    handle = head + tool_spec("scythe").length * motion.rotation[index, :, 2]
    return ToolDemo(head, handle, fps, "scythe", source="toolimit.scenes.spatial.sweep.pull_demonstration")
