"""Real-robot export: a smooth, limit-checked joint trajectory for open-loop execution (CSV + JSON)."""

from toolimit.deploy.export import (
    JointTrajectory,
    LimitViolation,
    check_trajectory,
    export_trajectory,
    load_trajectory,
    minimal_time_scale,
)
from toolimit.deploy.limits import SUPPORTED_ROBOTS, JointLimits, published_limits
from toolimit.deploy.resample import fit_joint_spline, resample

__all__ = [
    "SUPPORTED_ROBOTS",
    "JointLimits",
    "JointTrajectory",
    "LimitViolation",
    "check_trajectory",
    "export_trajectory",
    "fit_joint_spline",
    "load_trajectory",
    "minimal_time_scale",
    "published_limits",
    "resample",
]
