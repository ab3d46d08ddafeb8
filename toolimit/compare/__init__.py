"""Comparison against an outside solver: the base-placement tracking problem solved by Crocoddyl.

``tracking_problem`` defines the problem (a Pinocchio model whose first joints are the mobile base,
a tool frame, target poses, weights, limits) and evaluates its objective independently of any
solver. ``crocoddyl_models`` transcribes it into Crocoddyl action models and ``crocoddyl_tracking``
solves it with the box-constrained FDDP; they need the optional dependency
(``pip install -e ".[compare]"``), imported only when a solve is asked for.
"""

from toolimit.compare.crocoddyl_tracking import CrocoddylSolution, solve_with_crocoddyl
from toolimit.compare.tracking_problem import (
    BaseTrackingProblem,
    CostTerms,
    evaluate_cost,
    pose_residual,
    pose_residual_and_jacobian,
)

__all__ = [
    "BaseTrackingProblem",
    "CrocoddylSolution",
    "CostTerms",
    "evaluate_cost",
    "pose_residual",
    "pose_residual_and_jacobian",
    "solve_with_crocoddyl",
]
