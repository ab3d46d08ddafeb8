"""How far a policy's motions go past the robot's own joint limits, measured on its rollouts.

The paper says its policies respect the robot's joint velocity limits. This measures it on every
evaluated episode, from the joints at the control steps (finite differences, the arm at rest before
the start): the share of steps with any joint past its velocity limit (the model's) or its
acceleration limit (the published one, where the manufacturer publishes it: the Panda), and each
quantity's largest ratio to its limit. A policy learnt within the robot's bound
(:mod:`toolimit.robots.motion_bound`) stays at or below 0.95 of both; one learnt with the
authors' span of the action does not.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from toolimit.robots.limits import SUPPORTED_ROBOTS, published_limits
from toolimit.robots.model import RobotModel
from toolimit.robots.motion_bound import motion_from_rest

#: Ratios to a limit up to this count as within it: the rounding of a motion at the limit.
_ROUNDING = 1e-9


@dataclass(frozen=True)
class LimitUse:
    """Per episode (E,): the share of control steps with any joint past its velocity or
    acceleration limit, and the largest |velocity| / limit and |acceleration| / limit (None
    without a published acceleration limit)."""

    share_past: np.ndarray
    velocity_ratio: np.ndarray
    acceleration_ratio: np.ndarray | None

    def record(self) -> dict[str, Any]:
        """JSON-ready summary: the mean share and the largest ratios over the episodes, and each
        episode's share."""
        return {
            "share_of_steps_past_limits": float(np.mean(self.share_past)),
            "max_velocity_ratio": float(np.max(self.velocity_ratio)),
            "max_acceleration_ratio": None
            if self.acceleration_ratio is None
            else float(np.max(self.acceleration_ratio)),
            "share_of_steps_past_limits_per_episode": self.share_past.tolist(),
        }


def limit_use(joints: np.ndarray, dt: float, robot: RobotModel) -> LimitUse:
    """The limit use of episodes' joints (E, H+1, N) rad, one sample every ``dt`` s, on ``robot``."""
    velocity, acceleration = motion_from_rest(np.asarray(joints, dtype=float), dt)  # (E, H, N) each
    velocity_ratio = np.abs(velocity) / robot.velocity_limit
    past = np.any(velocity_ratio > 1 + _ROUNDING, axis=2)
    acceleration_ratio = None
    if robot.name in SUPPORTED_ROBOTS:
        ratios = np.abs(acceleration) / published_limits(robot.name).acceleration
        past |= np.any(ratios > 1 + _ROUNDING, axis=2)
        acceleration_ratio = ratios.max(axis=(1, 2))
    return LimitUse(past.mean(axis=1), velocity_ratio.max(axis=(1, 2)), acceleration_ratio)
