"""What a robot's joints can do in one control step: the bound on a commanded joint velocity.

The paper's robot is kinematic: its joints move at the commanded velocity for one control step. A
real arm cannot change its velocity faster than its acceleration limits, nor stop past a position
limit. :class:`MotionBound` applies both to a commanded velocity, given the velocity of the step
before: the velocity changes by at most ``acceleration * dt`` in a step and never exceeds the speed
from which braking at that acceleration stops inside the position range. A motion stepped through
it is one the robot can execute at its own timing: :mod:`toolimit.deploy.export` streams it with no
slowing down. For a robot with published limits (:mod:`toolimit.robots.limits`) the bound is those
limits within the export's margins; for the others, the model's position and velocity limits with
no acceleration bound (none is published). The step is compiled (numba, cached on disk like
:mod:`toolimit.rotations`): stage iii steps every path it tries through it, one sample at a time.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numba as nb
import numpy as np

from toolimit.robots.limits import SUPPORTED_ROBOTS, JointLimits, Margins, published_limits
from toolimit.robots.model import RobotModel


@dataclass(frozen=True)
class MotionBound:
    """The joints' range and what one step may command (arrays (N,), in the robot's joint order).

    Attributes:
        lower, upper: position range, rad.
        velocity: the largest |joint velocity|, rad/s (the velocity of an action of 1).
        acceleration: the largest |change of joint velocity| per second, rad/s^2; None: no bound.
    """

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray | None

    @classmethod
    def of(cls, robot: RobotModel, speed: float | None = None, margins: Margins = Margins()) -> MotionBound:
        """The bound of ``robot`` (module docstring). ``speed``: every joint's velocity bound, rad/s,
        and no acceleration bound, in the model's position range instead (the authors' span of
        the action, beyond the Panda's own limits)."""
        if speed is not None:
            return cls(robot.lower.copy(), robot.upper.copy(), np.full(robot.n_joints, float(speed)), None)
        if robot.name not in SUPPORTED_ROBOTS:
            return cls.model(robot)
        limits = published_limits(robot.name).within(margins)
        if limits.joint_names != tuple(robot.joint_names):
            raise ValueError(
                f"{robot.name}'s published limits name joints {limits.joint_names}, not {robot.joint_names}"
            )
        return cls(
            np.maximum(limits.position_lower, robot.lower),
            np.minimum(limits.position_upper, robot.upper),
            np.minimum(limits.velocity, robot.velocity_limit),
            limits.acceleration,
        )

    @classmethod
    def model(cls, robot: RobotModel) -> MotionBound:
        """The model's own position and velocity limits, no acceleration bound (the paper's robot)."""
        return cls(robot.lower.copy(), robot.upper.copy(), robot.velocity_limit.copy(), None)

    @classmethod
    def of_limits(cls, limits: JointLimits) -> MotionBound:
        """The position, velocity and acceleration limits of ``limits`` (its jerk aside)."""
        return cls(limits.position_lower, limits.position_upper, limits.velocity, limits.acceleration)

    def holds(self, q: np.ndarray, dt: float) -> bool:
        """Whether the joint path q (T+1, N) rad, one sample every ``dt`` s from rest, keeps the
        range, the velocity and (if bounded) the acceleration, finite differences (rounding aside)."""
        velocity, acceleration = motion_from_rest(q, dt)
        if np.any((q < self.lower) | (q > self.upper)) or np.any(np.abs(velocity) > self.velocity * (1 + 1e-12)):
            return False
        return self.acceleration is None or bool(np.all(np.abs(acceleration) <= self.acceleration * (1 + 1e-9)))

    def step(
        self, q: np.ndarray, previous: np.ndarray, commanded: np.ndarray, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """The joints (B, N) rad and their velocity (B, N) rad/s after one step of ``dt`` s from
        ``q`` (B, N) moving at ``previous`` (B, N), commanded ``commanded`` (B, N) rad/s."""
        q, previous, commanded = (np.ascontiguousarray(a, dtype=float) for a in (q, previous, commanded))
        moved, velocity = np.empty_like(q), np.empty_like(q)
        _step_rows(q, previous, commanded, float(dt), *self._compiled, moved, velocity)
        return moved, velocity

    def follow(self, path: np.ndarray, dt: float) -> np.ndarray:
        """(T+1, N) rad: the joints stepped from ``path[0]`` at rest, each step commanding the
        velocity that reaches the path's next sample, ``path`` (T+1, N) rad, one sample every ``dt`` s."""
        return _follow(np.ascontiguousarray(path, dtype=float), float(dt), *self._compiled)

    @functools.cached_property
    def _compiled(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, bool]:
        """The compiled step's bound: range, velocity, acceleration (zeros when unbounded), bounded;
        made once per bound, not at every step of the learner's simulator."""
        unbounded = np.zeros_like(self.velocity) if self.acceleration is None else self.acceleration
        lower, upper, velocity, acceleration = (
            np.ascontiguousarray(a, dtype=float) for a in (self.lower, self.upper, self.velocity, unbounded)
        )
        return lower, upper, velocity, acceleration, self.acceleration is not None

    def braking(self, q: np.ndarray, dt: float) -> np.ndarray:
        """(K, N) joint samples, one every ``dt`` s, that continue the path q (T+1, N) rad from its last
        step's velocity, slowing by the acceleration bound each step, until every joint can stop
        within one more step (none for a path that ends that slowly, or with no acceleration bound:
        such a robot stops within a step)."""
        q = np.asarray(q, dtype=float)
        if self.acceleration is None or len(q) < 2:
            return q[:0]
        position, velocity = q[-1:], (q[-1:] - q[-2:-1]) / dt
        one_step = self.acceleration * dt * (1.0 + 1e-9)
        tail = []
        while np.any(np.abs(velocity) > one_step):
            position, velocity = self.step(position, velocity, np.zeros_like(velocity), dt)
            tail.append(position[0])
        return np.array(tail).reshape(-1, q.shape[1])


def motion_from_rest(q: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The velocities (rad/s) and accelerations (rad/s^2), both (..., T, N), of joint paths q
    (..., T+1, N) rad sampled every ``dt`` s, by finite differences with the arm at rest before the
    first sample."""
    velocity = np.diff(q, axis=-2) / dt
    at_rest = np.zeros_like(velocity[..., :1, :])
    return velocity, np.diff(np.concatenate([at_rest, velocity], axis=-2), axis=-2) / dt


_jit = nb.njit(cache=True, nogil=True, fastmath=False, error_model="numpy")


@_jit
def _braking_speed(room, change, dt):  # type: ignore[no-untyped-def]
    """The largest speed (rad/s) for this step from which slowing by ``change`` rad/s every step
    after it moves at most ``room`` rad in all: the steps' speeds v, v - u, v - 2u, ... (u =
    ``change``) over their positive part, each for ``dt`` s. The n + 1 steps of a speed in
    [n u, (n + 1) u] cover dt ((n + 1) v - u n (n + 1) / 2); n is the most whole steps of u that fit."""
    whole = np.floor((np.sqrt(1.0 + 8.0 * room / (dt * change)) - 1.0) / 2.0)
    return (room / dt + change * whole * (whole + 1.0) / 2.0) / (whole + 1.0)


@_jit
def _step_rows(q, previous, commanded, dt, lower, upper, velocity, acceleration, bounded, moved, moved_velocity):  # type: ignore[no-untyped-def]
    """:meth:`MotionBound.step` of every row of q, previous, commanded (B, N) into moved and
    moved_velocity (B, N): the commanded velocity within the velocity bound; with ``bounded``,
    within ``acceleration * dt`` of the previous one and never faster towards a range's end than
    braking at the bound stops before it (braking harder than the bound allows is never asked);
    the move within the range."""
    for b in range(q.shape[0]):
        for j in range(q.shape[1]):
            v = min(max(commanded[b, j], -velocity[j]), velocity[j])
            if bounded:
                change = acceleration[j] * dt
                slowest, fastest = previous[b, j] - change, previous[b, j] + change
                up = _braking_speed(max(upper[j] - q[b, j], 0.0), change, dt)
                down = _braking_speed(max(q[b, j] - lower[j], 0.0), change, dt)
                fastest = min(fastest, max(up, slowest))
                slowest = max(slowest, min(-down, fastest))
                v = min(max(v, slowest), fastest)
            moved[b, j] = min(max(q[b, j] + v * dt, lower[j]), upper[j])
            moved_velocity[b, j] = (moved[b, j] - q[b, j]) / dt


@_jit
def _follow(path, dt, lower, upper, velocity, acceleration, bounded):  # type: ignore[no-untyped-def]
    """:meth:`MotionBound.follow`."""
    followed = path.copy()
    n = path.shape[1]
    previous, moved, moved_velocity = np.zeros((1, n)), np.empty((1, n)), np.empty((1, n))
    bound = (lower, upper, velocity, acceleration, bounded)
    for t in range(1, path.shape[0]):
        commanded = (path[t : t + 1] - followed[t - 1 : t]) / dt
        _step_rows(followed[t - 1 : t], previous, commanded, dt, *bound, moved, moved_velocity)
        followed[t] = moved[0]
        previous[:] = moved_velocity
    return followed
