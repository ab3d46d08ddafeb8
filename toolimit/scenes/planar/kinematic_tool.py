"""A 3D tool pose driven as kinematic pymunk bodies in a planar world (one body per instance).

Plane mapping (orthographic projection, the coordinate normal to the plane is dropped):

* ``"xz"`` (vertical plane, spade and hammer): pymunk (x, y) = world (x, z); world y is ignored.
* ``"xy"`` (horizontal plane, scythe): pymunk (x, y) = world (x, y); world z is ignored here (the
  scythe scene checks heights itself).

The body origin is the tool head point projected into the plane. The body angle is the in-plane
angle of one tool axis (``reference_axis``: 0 = tool x, 2 = tool z) projected into the plane; when
that axis is nearly normal to the plane (projection shorter than 1e-3) the previous angle is kept.
Each tool part is given in the tool frame (metres) and projected, so the planar outline is the
shadow of the 3D part: a spade whose working direction x points out of the plane loses its lip,
a tool pointing out of the plane shrinks.

Motion over a control step: the body gets the constant velocity and angular velocity that take it
from its pose to the target pose in ``control_dt`` (so contacts see the true tool speed and
momentum is transferred), pymunk integrates it over the sub-steps, and the pose is snapped to the
target at the end (removing round-off). The first step after a reset places the tool at rest.
Changes of the projected outline itself (the tool turning out of the plane, a new roll) are applied
at the start of a step, as a change of shape without velocity.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pymunk

from toolimit.scenes.base import batched_pose
from toolimit.tools import ToolPose

Plane = Literal["xz", "xy"]

#: World axes (indices into x, y, z) that become pymunk x and y.
PLANE_AXES: dict[str, tuple[int, int]] = {"xz": (0, 2), "xy": (0, 1)}


def to_plane(points: np.ndarray, plane: Plane) -> np.ndarray:
    """World points or vectors (..., 3) as plane coordinates (..., 2), metres."""
    return np.asarray(points, dtype=float)[..., list(PLANE_AXES[plane])]


def plane_point(point: np.ndarray) -> tuple[float, float]:
    """A (2,) plane point or vector as the pair of floats pymunk takes."""
    return float(point[0]), float(point[1])


def _wrap_angle(angle: np.ndarray) -> np.ndarray:
    """Angles (rad) wrapped to [-pi, pi)."""
    return (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi


class KinematicTool:
    """B kinematic bodies, one per pymunk space, that follow tool poses projected into a plane.

    Attributes:
        plane: "xz" or "xy" (see the module docstring).
        reference_axis: tool axis (0 = x, 1 = y, 2 = z) whose projection gives the body angle.
        bodies: the kinematic bodies, one per instance.
        placed: False until the first target pose has been applied.
        position: (B, 2) body origins (head point in the plane) after the last step, m.
        angle: (B,) body angles after the last step, rad.
        pose: the last target tool pose (B, 3) and (B, 3, 3), world frame, or None before the first.
    """

    def __init__(self, spaces: list[pymunk.Space], plane: Plane, reference_axis: int):
        self.plane = plane
        self.reference_axis = reference_axis
        self.bodies = [pymunk.Body(body_type=pymunk.Body.KINEMATIC) for _ in spaces]
        for space, body in zip(spaces, self.bodies):
            space.add(body)
        self.placed = False
        self.position = np.zeros((len(spaces), 2))
        self.angle = np.zeros(len(spaces))
        self.pose: tuple[np.ndarray, np.ndarray] | None = None
        self._target = (self.position, self.angle)  # (B, 2) m and (B,) rad at the end of the step

    @property
    def batch_size(self) -> int:
        return len(self.bodies)

    def _target_angle(self, rotation: np.ndarray) -> np.ndarray:
        """(B,) in-plane angle of the reference axis of rotations (B, 3, 3); previous if degenerate."""
        axis = to_plane(rotation[:, :, self.reference_axis], self.plane)
        length = np.linalg.norm(axis, axis=-1)
        angle = np.arctan2(axis[:, 1], axis[:, 0])
        return np.where(length > 1e-3, angle, self.angle)

    def local_points(self, points: np.ndarray) -> np.ndarray:
        """Tool-frame points (K, 3) as body-local plane points (B, K, 2) at the step's target pose.

        Call after :meth:`begin_step`; shapes built from these points take the projected outline.
        """
        if self.pose is None:
            raise RuntimeError("the tool has no pose before the first step")
        rotation = self.pose[1]
        planar = to_plane(np.einsum("bij,kj->bki", rotation, points), self.plane)  # head -> point
        angle = self._target[1]
        cos, sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
        return np.stack([cos * planar[..., 0] + sin * planar[..., 1], -sin * planar[..., 0] + cos * planar[..., 1]], -1)

    def begin_step(self, tool_pose: ToolPose, control_dt: float) -> None:
        """Set each body's velocity so that it reaches ``tool_pose`` after ``control_dt`` seconds.

        The first call after construction places the bodies there at rest instead.
        """
        position3, rotation = batched_pose(tool_pose, self.batch_size)
        target_position = to_plane(position3, self.plane)
        target_angle = self._target_angle(rotation)
        if not self.placed:
            velocity = np.zeros_like(target_position)
            angular_velocity = np.zeros_like(target_angle)
            self.position, self.angle = target_position, target_angle
            for body, p, a in zip(self.bodies, target_position, target_angle):
                body.position = plane_point(p)
                body.angle = float(a)
            self.placed = True
        else:
            velocity = (target_position - self.position) / control_dt
            angular_velocity = _wrap_angle(target_angle - self.angle) / control_dt
        for body, v, w in zip(self.bodies, velocity, angular_velocity):
            body.velocity = plane_point(v)
            body.angular_velocity = float(w)
        self._target = (target_position, self.angle + angular_velocity * control_dt)
        self.pose = (position3, rotation)

    def end_step(self) -> None:
        """Snap the bodies onto the target pose of the step (removes integration round-off)."""
        target_position, target_angle = self._target
        for body, p, a in zip(self.bodies, target_position, target_angle):
            body.position = (float(p[0]), float(p[1]))
            body.angle = float(a)
        self.position, self.angle = target_position, target_angle

    def world_points(self, points: np.ndarray) -> np.ndarray:
        """Tool-frame points (K, 3) at the last target pose as world points (B, K, 3), metres."""
        if self.pose is None:
            raise RuntimeError("the tool has no pose before the first step")
        position, rotation = self.pose
        return position[:, None, :] + np.einsum("bij,kj->bki", rotation, points)

    def plane_point(self, point: np.ndarray) -> np.ndarray | None:
        """The tool-frame point (3,) at the last target pose in the plane (B, 2), metres; None
        before the first step."""
        if self.pose is None:
            return None
        return to_plane(self.world_points(np.asarray(point, dtype=float)[None])[:, 0], self.plane)
