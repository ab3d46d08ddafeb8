"""Stage (iii): sequential-QP (OSQP) tracking of a tool trajectory with base placement.

``track(robot, targets, TrackOptions(...))`` optimises the base and the joint velocities of
``robot`` (:func:`toolimit.robots.make_robot`) so that its tool frame follows ``targets``
(:class:`PoseTargets`), with hard joint position and velocity limits; see :mod:`.problem` for the
cost, :mod:`.sqp` for the solver and :mod:`.track` for the multi-start.
``select_by_robot_execution`` (:mod:`.selection`) picks, among the alignment's candidates, the one
whose robot replay earns the most goal reward.
"""

from toolimit.trajopt.execution import execute_in_scene
from toolimit.trajopt.problem import PoseTargets, TrackingProblem, TrackingWeights
from toolimit.trajopt.reachability import reachable_steps
from toolimit.trajopt.result import TrajectoryResult
from toolimit.trajopt.selection import select_by_robot_execution
from toolimit.trajopt.sqp import SqpOptions, SqpOutcome, solve_sqp
from toolimit.trajopt.targets import from_original_spade_tip, load_pose_targets, targets_from_alignment
from toolimit.trajopt.time_scale import TIME_SCALE_GRID, choose_time_scale
from toolimit.trajopt.track import TrackOptions, base_guesses, track

__all__ = [
    "PoseTargets",
    "SqpOptions",
    "SqpOutcome",
    "TIME_SCALE_GRID",
    "TrackOptions",
    "TrackingProblem",
    "TrackingWeights",
    "TrajectoryResult",
    "base_guesses",
    "choose_time_scale",
    "execute_in_scene",
    "from_original_spade_tip",
    "load_pose_targets",
    "reachable_steps",
    "select_by_robot_execution",
    "solve_sqp",
    "targets_from_alignment",
    "track",
]
