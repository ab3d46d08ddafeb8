"""Real-robot export: a joint path retimed within the robot's published limits, sampled for streaming (CSV + JSON).

``retime(q, dt, limits)`` is the library entry point for any joint path (an optimised trajectory, a
policy's rollout): it returns a :class:`RetimedPath` whose ``sample(rate)`` gives the commands.
``replay_open_loop(times, positions, task)`` runs such commands in a learning task's scene with no
policy in the loop, as the paper runs its policies' trajectories on the real robot.
"""

from toolimit.deploy.export import ExportPlan, export_trajectory, plan_export
from toolimit.deploy.open_loop import OpenLoopResult, replay_open_loop
from toolimit.deploy.retime import RetimedPath, SampledTrajectory, retime
from toolimit.errors import PathOutsideLimits
from toolimit.robots.limits import SUPPORTED_ROBOTS, JointLimits, Margins, published_limits
from toolimit.trajopt.result import JointTrajectory, load_trajectory

__all__ = [
    "SUPPORTED_ROBOTS",
    "ExportPlan",
    "JointLimits",
    "JointTrajectory",
    "Margins",
    "OpenLoopResult",
    "PathOutsideLimits",
    "RetimedPath",
    "SampledTrajectory",
    "export_trajectory",
    "load_trajectory",
    "plan_export",
    "published_limits",
    "replay_open_loop",
    "retime",
]
