"""Hand-made hammer strikes for the 3D hammer scene (tests, LfD baseline).

A motion generator, kept apart from the scene it is made for: it reads the nail's position and the
hammer's geometry, and returns tool poses any scene replay can follow. The hammer is held face down
(tool x, the striking direction, along world -z) with its handle level (tool z horizontal), so the
face meets the nail head's plate square on; the tool origin, the head's centre, is ``FACE_OFFSET``
above the face.
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.base import CONTROL_FPS, SceneParams
from toolimit.scenes.spatial.hammer import PROTRUSION
from toolimit.tools import ToolPose, hold_last, tool_spec

#: Head centre (tool origin) to the striking face along tool x, m.
FACE_OFFSET = tool_spec("hammer").head_width / 2


def face_down(handle_heading: np.ndarray) -> np.ndarray:
    """(3, 3) tool rotation with the face down (tool x = world -z) and the handle along
    ``handle_heading`` (3,), a horizontal unit vector from the head towards the handle (tool z)."""
    x = np.array([0.0, 0.0, -1.0])
    z = np.asarray(handle_heading, dtype=float)
    return np.column_stack([x, np.cross(z, x), z])


def face_poses(nail_xy: np.ndarray, faces: np.ndarray, rotation: np.ndarray) -> ToolPose:
    """(T,) poses of the hammer turned by ``rotation`` (3, 3) with its face over ``nail_xy`` (2,) m
    at heights ``faces`` (T,) (world z, m)."""
    positions = np.column_stack([np.broadcast_to(nail_xy, (len(faces), 2)), np.asarray(faces) + FACE_OFFSET])
    return ToolPose(positions, np.repeat(rotation[None], len(faces), axis=0))


def strike_descent(
    nail_xy: np.ndarray, bottom: float, speed: float, steps: int, dt: float, rotation: np.ndarray
) -> ToolPose:
    """``steps + 1`` poses lowering the face straight down over ``nail_xy`` (2,) m at ``speed`` m/s,
    one every ``dt`` s, from ``bottom + steps * speed * dt`` to ``bottom`` (face height, world z,
    m); the hammer turned by ``rotation`` (3, 3) (e.g. :func:`face_down`)."""
    return face_poses(nail_xy, bottom + (steps - np.arange(steps + 1)) * speed * dt, rotation)


def scripted_strike(
    params: SceneParams,
    fps: float = CONTROL_FPS,
    strikes: int = 2,
    speed: float = 2.0,
    lift: float = 0.15,
    overshoot: float = 0.01,
) -> ToolPose:
    """Hand-made strikes that plant the nail at ``params["nail_position"]`` within the first second.

    The hammer starts face down ``lift`` (m) above the nail head's top; each strike lowers the face
    at up to ``speed`` (m/s) to an equal share of the nail's travel (``PROTRUSION`` plus
    ``overshoot``, m) below that top, so the last one ends past the board whatever the glide of
    the nail, then lifts it back in 0.25 s; after the last strike the hammer holds 0.25 s. Two
    strikes at 2 m/s plant the nail 0.5 s after the placement. The handle points from the nail
    towards the world origin (where the robot's first base guess stands; -x for a nail above it).
    Returns (T, 3) head positions and (T, 3, 3) rotations (world frame) at ``fps``.
    """
    if strikes < 1 or not speed > 0 or not lift > 0:
        raise ValueError(f"strikes >= 1, speed > 0 and lift > 0 expected, got {strikes}, {speed}, {lift}")
    nail = np.asarray(params["nail_position"], dtype=float)
    xy, top = nail[:2], float(nail[2])
    distance = float(np.linalg.norm(xy))
    rotation = face_down(np.array([*(-xy / distance), 0.0]) if distance > 0.01 else np.array([-1.0, 0.0, 0.0]))
    dt = 1.0 / fps
    raised = top + lift
    rise_steps = int(np.ceil(0.25 * fps))
    pieces = [face_poses(xy, np.array([raised]), rotation)]
    for k in range(1, strikes + 1):
        bottom = top - k * (PROTRUSION + overshoot) / strikes
        steps = int(np.ceil((raised - bottom) / (speed * dt)))
        descent = strike_descent(xy, bottom, (raised - bottom) / (steps * dt), steps, dt, rotation)
        pieces.append(ToolPose(descent.position[1:], descent.rotation[1:]))  # its first pose: the raised one
        pieces.append(face_poses(xy, np.linspace(bottom, raised, rise_steps + 1)[1:], rotation))
    return hold_last(ToolPose(*(np.concatenate(arrays) for arrays in zip(*pieces))), rise_steps)
