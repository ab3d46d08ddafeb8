"""A hand-made scythe draw for the 3D scythe scene (tests, the LfD baseline's demonstration).

A motion generator, kept apart from the scene it is made for: it reads the grass patch's
parameters and the scythe's geometry, and returns tool poses any scene replay can follow. The
authors' rule (:mod:`toolimit.scenes.scythe_cut`) cuts with the blade's side towards the handle,
moving towards the handle at more than 1 m/s, with the snath within 30 degrees of horizontal.

The blade (0.35 m) is shorter than the patch (0.4 x 0.1 m), so a pull across the patch's width
leaves stalks at its ends. :func:`scripted_sweep` draws along the patch's length instead: the blade
level across the patch (tool x along world -y), the snath along world x with the handle towards -x,
raised :data:`SNATH_ELEVATION`, pulled towards the handle (world -x) over the patch and
:data:`DRAW_MARGIN` beyond each end at :data:`DRAW_SPEED`. The speed rises from rest over a run-up
of :data:`RAMP` and falls back over as long a run-out, a half cosine each, so that a robot arm can
follow it: it is the LfD baseline's kinesthetic demonstration (:mod:`toolimit.learn.kinesthetic`).
Its speed and run-up are the ones with which the Panda's replay cuts nearly every stalk (a shorter
run-up or a faster draw leaves the arm lagging); the measurements and the motion this replaced are
in docs/history.md#scenes.
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.base import CONTROL_FPS, SceneParams
from toolimit.scenes.scythe_cut import PATCH_SIZE, scythe_cut_rule
from toolimit.tools import ToolPose, hold_last, rotation_z

#: World-from-tool rotation of the level scythe: tool x = world x, tool y = world z, tool z = -y.
LEVEL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
#: How far the scripted draw raises the snath above horizontal (rad), turning about the blade.
SNATH_ELEVATION = np.deg2rad(20.0)
#: The scripted draw's speed over the patch (m/s; the rule's approach needs more than 1 m/s).
DRAW_SPEED = 1.5
#: Run-up and run-out of the scripted draw (m), over which its speed rises from and falls to rest.
RAMP = 0.35
#: How far beyond each end of the patch the scripted draw keeps its full speed (m).
DRAW_MARGIN = 0.05


def raised(elevation: float) -> np.ndarray:
    """World-from-tool rotation of the scythe with its snath raised ``elevation`` rad from
    :data:`LEVEL` (about the blade, world x: the handle end goes up)."""
    c, s = np.cos(elevation), np.sin(elevation)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]]) @ LEVEL


def edge_centre_offset(rotation: np.ndarray) -> np.ndarray:
    """(3,) the cutting edge's centre relative to the head point (the pose's position), world, m,
    for the world-from-tool ``rotation`` (3, 3)."""
    return rotation @ scythe_cut_rule(0.005).edge.mean(axis=0)


def pull(
    edge_centre: np.ndarray, start_y: float, end_y: float, speed: float, dt: float, elevation: float = 0.0
) -> ToolPose:
    """Poses every ``dt`` s of the scythe (snath raised ``elevation`` rad, :func:`raised`) whose
    cutting edge's centre moves along world y from ``start_y`` to ``end_y`` (m) at ``speed`` (m/s),
    at x and height of ``edge_centre`` (3,) m."""
    rotation = raised(elevation)
    steps = max(1, int(np.ceil(abs(end_y - start_y) / (speed * dt))))
    y = np.linspace(start_y, end_y, steps + 1)
    centres = np.column_stack([np.full(steps + 1, edge_centre[0]), y, np.full(steps + 1, edge_centre[2])])
    return ToolPose(centres - edge_centre_offset(rotation), np.repeat(rotation[None], steps + 1, axis=0))


def ramped_distances(speed: float, ramp: float, cruise: float, dt: float) -> np.ndarray:
    """(T,) distances (m) travelled every ``dt`` s by a motion from rest whose speed rises to
    ``speed`` (m/s) over ``ramp`` m (a half cosine), holds over ``cruise`` m and falls back to rest
    over ``ramp`` m; the last sample is the whole distance."""
    rise = 2.0 * ramp / speed  # s: a half cosine's mean speed is half its top
    total = 2.0 * rise + cruise / speed

    def ramped(t: np.ndarray) -> np.ndarray:  # distance after t s of rising speed, t <= rise
        return speed / 2.0 * (t - rise / np.pi * np.sin(np.pi * t / rise))

    t = np.minimum(np.arange(int(np.ceil(total / dt)) + 1) * dt, total)
    cruising = ramp + speed * (t - rise)
    return np.where(t < rise, ramped(t), np.where(t <= total - rise, cruising, 2.0 * ramp + cruise - ramped(total - t)))


def scripted_sweep(
    params: SceneParams, fps: float = CONTROL_FPS, speed: float = DRAW_SPEED, height: float = 0.05
) -> ToolPose:
    """The draw of the module docstring along the patch at ``grass_position``, cutting every stalk
    within the first second: one still step, the run-up, the patch crossed at ``speed`` m/s with
    the edge ``height`` m above the ground, the run-out, then held still 0.25 s. Returns (T, 3)
    head positions and (T, 3, 3) rotations (world frame) at ``fps``."""
    patch = np.asarray(params["grass_position"], dtype=float)
    rotation = rotation_z(-np.pi / 2) @ raised(SNATH_ELEVATION)
    towards_handle = rotation[:, 2] * [1.0, 1.0, 0.0]  # the snath's horizontal direction, world: -x
    towards_handle /= np.linalg.norm(towards_handle)
    cruise = PATCH_SIZE[0] + 2.0 * DRAW_MARGIN
    distances = ramped_distances(speed, RAMP, cruise, 1.0 / fps)
    start = np.array([patch[0], patch[1], height]) - towards_handle * (RAMP + cruise / 2.0)
    centres = start + np.outer(np.concatenate([[0.0], distances]), towards_handle)
    motion = ToolPose(centres - edge_centre_offset(rotation), np.repeat(rotation[None], len(centres), axis=0))
    return hold_last(motion, int(np.ceil(0.25 * fps)))
