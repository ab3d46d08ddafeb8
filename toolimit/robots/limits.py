"""Published joint limits of real robots, and the check of a sampled joint trajectory against them.

Only robots whose manufacturer publishes position, velocity, acceleration AND jerk limits per
joint are supported: a real-robot export must not guess any of them.

* ``panda``: Franka Emika Panda, "Robot and interface specifications" of the Franka Control
  Interface documentation (frankaemika.github.io/docs/control_parameters.html), the limits in joint
  space: q_min/q_max (rad), dq_max (rad/s), ddq_max (rad/s^2), dddq_max (rad/s^3).

The UR5 is not supported: Universal Robots publish joint ranges (+-360 deg) and maximum speeds
(180 deg/s) but no joint acceleration or jerk limits.

:class:`Margins` says how far inside the published limits a robot is commanded: Franka's
documentation states the limits as strict inequalities and aborts a motion that reaches one, and
its users scale velocity and acceleration below them. The same margins bound what a learnt policy
may command in simulation (:class:`MotionBound`) and what the export streams, so that the motion
that succeeded in simulation is the one the robot executes, with no slowing down.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from toolimit.errors import InputError

QUANTITIES = ("position", "velocity", "acceleration", "jerk")
UNITS = {"position": "rad", "velocity": "rad/s", "acceleration": "rad/s^2", "jerk": "rad/s^3"}


@dataclass(frozen=True)
class JointLimits:
    """Per-joint limits of a real robot (arrays (N,), in the order of ``joint_names``).

    Attributes:
        robot: robot name.
        joint_names: (N,) joint names, as in the robot model.
        position_lower, position_upper: rad.
        velocity: |dq| max, rad/s.
        acceleration: |ddq| max, rad/s^2.
        jerk: |dddq| max, rad/s^3.
        source: where the numbers come from.
    """

    robot: str
    joint_names: tuple[str, ...]
    position_lower: np.ndarray
    position_upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    source: str

    def within(self, margins: Margins) -> JointLimits:
        """These limits narrowed by ``margins``: positions moved inwards, derivatives scaled down."""
        lower = self.position_lower + margins.position
        upper = self.position_upper - margins.position
        if np.any(lower >= upper):
            raise InputError(f"a position margin of {margins.position} rad leaves no range on a joint of {self.robot}")
        return JointLimits(
            robot=self.robot,
            joint_names=self.joint_names,
            position_lower=lower,
            position_upper=upper,
            velocity=self.velocity * margins.velocity,
            acceleration=self.acceleration * margins.acceleration,
            jerk=self.jerk * margins.jerk,
            source=f"{self.source}, within {margins.describe()}",
        )

    def as_dict(self) -> dict:
        return {
            "robot": self.robot,
            "source": self.source,
            "joint_names": list(self.joint_names),
            "position_lower_rad": self.position_lower.tolist(),
            "position_upper_rad": self.position_upper.tolist(),
            "velocity_rad_s": self.velocity.tolist(),
            "acceleration_rad_s2": self.acceleration.tolist(),
            "jerk_rad_s3": self.jerk.tolist(),
        }


#: The largest position margin, rad: a margin, not another range.
MAX_POSITION_MARGIN = 0.5


class MarginError(InputError):
    """A margin no export can use: ``args`` are the margin's name and the problem."""

    def __str__(self) -> str:
        return f"{self.args[0]} margin {self.args[1]}"


@dataclass(frozen=True)
class Margins:
    """How far inside a robot's published limits it is commanded (see the module docstring).

    Attributes:
        position: rad kept from each end of every joint's range.
        velocity, acceleration, jerk: fractions of the published limits, in (0, 1].
    """

    position: float = 0.01
    velocity: float = 0.95
    acceleration: float = 0.95
    jerk: float = 0.95

    def __post_init__(self) -> None:
        if not 0.0 <= self.position <= MAX_POSITION_MARGIN:
            raise MarginError("position", f"must be between 0 and {MAX_POSITION_MARGIN} rad, got {self.position}")
        for name in ("velocity", "acceleration", "jerk"):
            scale = getattr(self, name)
            if not 0.0 < scale <= 1.0:
                raise MarginError(name, f"must be a fraction of the limit in (0, 1], got {scale}")

    def describe(self) -> str:
        return (
            f"{self.position:g} rad of the position limits and {self.velocity:g}, {self.acceleration:g}, "
            f"{self.jerk:g} of the velocity, acceleration and jerk limits"
        )

    def as_dict(self) -> dict[str, float]:
        return {
            "position_rad": self.position,
            "velocity_scale": self.velocity,
            "acceleration_scale": self.acceleration,
            "jerk_scale": self.jerk,
        }


_PANDA = JointLimits(
    robot="panda",
    joint_names=tuple(f"panda_joint{i}" for i in range(1, 8)),
    position_lower=np.array([-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]),
    position_upper=np.array([2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973]),
    velocity=np.array([2.1750, 2.1750, 2.1750, 2.1750, 2.6100, 2.6100, 2.6100]),
    acceleration=np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0]),
    jerk=np.array([7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0]),
    source="Franka Control Interface documentation, robot and interface specifications (joint space limits)",
)

_PUBLISHED = {"panda": _PANDA}
SUPPORTED_ROBOTS = tuple(_PUBLISHED)


def published_limits(robot: str) -> JointLimits:
    """The published limits of ``robot``; ValueError for robots without published jerk/acceleration limits."""
    try:
        return _PUBLISHED[robot]
    except KeyError:
        raise InputError(
            f"export supports only robots with published position, velocity, acceleration and jerk limits "
            f"({', '.join(SUPPORTED_ROBOTS)}); {robot!r} is not one of them"
        ) from None


@dataclass(frozen=True)
class QuantityCheck:
    """The worst sample of one quantity against its limit.

    ``ratio`` is |value| / limit for velocity, acceleration, jerk; for position it is the signed
    distance outside [lower, upper] in rad (negative: the smallest margin inside). ``passed`` is
    True when nothing exceeds.
    """

    quantity: str
    passed: bool
    ratio: float
    joint: str
    time_s: float
    value: float
    limit: float

    def describe(self) -> str:
        unit = UNITS[self.quantity]
        if self.quantity == "position":
            return (
                f"{self.joint} position {self.value:.6g} {unit} at t = {self.time_s:.4f} s is outside its limit "
                f"{self.limit:.6g} {unit} (by {self.ratio:.3g} {unit})"
            )
        return (
            f"{self.joint} {self.quantity} {self.value:.6g} {unit} at t = {self.time_s:.4f} s exceeds the limit "
            f"+-{self.limit:.6g} {unit} ({self.ratio:.3g} times the limit)"
        )

    def as_dict(self) -> dict:
        return {
            "passed": self.passed,
            "worst_joint": self.joint,
            "time_s": self.time_s,
            "value": self.value,
            "limit": self.limit,
            ("outside_by_rad" if self.quantity == "position" else "max_ratio"): self.ratio,
        }


def check_samples(limits: JointLimits, times: np.ndarray, samples: dict[str, np.ndarray]) -> list[QuantityCheck]:
    """Check ``samples[quantity]`` (K, N) at ``times`` (K,) s against ``limits``, one result per quantity."""
    checks = []
    for quantity in QUANTITIES:
        values = samples[quantity]
        if quantity == "position":
            below = limits.position_lower - values
            above = values - limits.position_upper
            excess = np.maximum(below, above)
            k, j = np.unravel_index(np.argmax(excess), excess.shape)
            limit = limits.position_lower[j] if below[k, j] > above[k, j] else limits.position_upper[j]
            ratio = float(excess[k, j])
            passed = ratio <= 0.0
        else:
            bound = getattr(limits, quantity)
            ratios = np.abs(values) / bound
            k, j = np.unravel_index(np.argmax(ratios), ratios.shape)
            limit = float(bound[j])
            ratio = float(ratios[k, j])
            passed = ratio <= 1.0
        checks.append(
            QuantityCheck(
                quantity, passed, ratio, limits.joint_names[j], float(times[k]), float(values[k, j]), float(limit)
            )
        )
    return checks
