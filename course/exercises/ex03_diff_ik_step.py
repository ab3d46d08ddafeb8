"""Exercise 03: one differential-IK step as a quadratic program solved with OSQP (stage iii in small).

Trajectory optimisation (``toolimit.trajopt``) solves one large QP over the whole horizon; here you
write the one-step version that a reactive controller would run at every control tick.

Check your work with ``python grade.py check --exercise ex03`` in the course folder (in the
project's repository: ``python course/grade.py check --exercise ex03``); see README.md. Write the
function yourself: a submission that calls an existing implementation of it (toolimit's, a
dependency's, the course's) scores 0 for the exercise.
"""

from __future__ import annotations

import numpy as np

from toolimit.robots import RobotModel


def diff_ik_step(
    robot: RobotModel,
    q: np.ndarray,
    target_position: np.ndarray,
    target_rotation: np.ndarray,
    dt: float,
    pose_weights: np.ndarray,
    velocity_weight: float,
    base: np.ndarray | None = None,
) -> np.ndarray:
    """Return the joint velocity v (N,), rad/s, of one differential-IK step towards a target pose.

    The tool frame is at ``M(q)`` (world frame, ``robot.tool_placement_world(q, base)``); the target
    is ``P = SE3(target_rotation, target_position)`` (world frame). Solve

        min_v  |W (J v dt - e)|^2 + velocity_weight |v|^2
        s.t.   -vlim <= v <= vlim                (robot.velocity_limit, rad/s)
               lower <= q + v dt <= upper        (robot.lower, robot.upper, rad)

    where
      * ``e = log6(M(q)^-1 P)`` (6,) is the pose error expressed in the TOOL frame (LOCAL), linear
        part first (m), then angular (rad): ``pin.log6(M.actInv(P)).vector``;
      * ``J`` (6, N) is the tool-frame Jacobian in the same LOCAL frame with respect to the arm joints:
        ``robot.tool_jacobian(q, base, reference="local")`` has the 3 base columns first, drop them;
      * ``W = diag(pose_weights)`` (6,);
      * ``dt`` is the step duration in seconds: ``J v dt`` is the predicted motion over the step.

    Solve the QP with OSQP (``osqp.OSQP().setup(P, q, A, l, u, ...)``, P and A as scipy.sparse CSC;
    OSQP minimises 1/2 x'Px + q'x, so expand the squares and mind the factor 2). Use tight settings
    (``eps_abs=eps_rel=1e-9``, ``polishing=True``, ``verbose=False``) and check the status before
    using the answer (``result = solver.solve(raise_error=False)``, then
    ``result.info.status_val == osqp.SolverStatus.OSQP_SOLVED``): the grader compares your v with
    its own within 1e-4 rad/s and checks the constraints to 1e-6.

    Args:
        robot: a robot from ``toolimit.robots.make_robot`` (e.g. the Panda), N arm joints.
        q: (N,) current joint positions, radians, within the limits.
        target_position: (3,) target tool-frame origin, world frame, metres.
        target_rotation: (3, 3) target tool-frame orientation (columns = tool axes in world axes).
        dt: step duration, seconds (> 0).
        pose_weights: (6,) diagonal of W (3 linear, 3 angular).
        velocity_weight: w_v >= 0 (on rad/s).
        base: (3,) robot base (x m, y m, yaw rad); None means (0, 0, 0).

    Returns:
        (N,) float array: the joint velocities, rad/s.
    """
    raise NotImplementedError("exercise 03: solve the differential-IK QP with OSQP")
