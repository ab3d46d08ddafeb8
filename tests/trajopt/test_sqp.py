"""The SQP solver: recovers reachable trajectories, keeps hard limits exactly, stops when J stalls."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from toolimit.robots.motion_bound import MotionBound
from toolimit.trajopt import SqpOptions, TrackingProblem, TrackingWeights, solve_sqp
from toolimit.trajopt.sqp import project_to_limits

from trajopt_helpers import FPS, reachable_path, targets_of

# a tiny velocity weight: the exact path is then (nearly) optimal
PRECISE = TrackingWeights(position=1.0, rotation=0.5, velocity=1e-7)


@pytest.mark.parametrize("robot_name", ["planar3", "panda"])
def test_recovers_a_reachable_trajectory_and_its_base(robot_name, request):
    robot = request.getfixturevalue(robot_name)
    path = reachable_path(robot, 30)
    true_base = np.array([0.4, -0.3, 0.5]) * robot.base_dofs
    targets = targets_of(robot, path, true_base)
    # the model's limits: a random reachable path need not keep the Panda's acceleration bound
    problem = TrackingProblem(robot, targets, 1 / FPS, q_start=path[0], weights=PRECISE, bound=MotionBound.model(robot))
    guess = true_base + np.array([0.08, -0.05, 0.1]) * robot.base_dofs
    outcome = solve_sqp(problem, guess, SqpOptions(osqp_eps=1e-6))
    positions, _ = robot.tool_poses(outcome.q[1:], outcome.base)
    errors = np.linalg.norm(positions - targets.positions, axis=1)
    # base + arm are redundant for the pose (4 DoF for planar3's 3, 10 for panda's 6), so the
    # base itself need not come back: the tool path must
    assert outcome.cost < 1e-3 * outcome.cost_history[0]
    assert np.median(errors) < 1e-3, f"median error {np.median(errors):.2e} m"
    assert np.max(errors) < 5e-3, f"max error {np.max(errors):.2e} m"
    assert np.all(np.diff(outcome.cost_history) <= 0), "J must decrease monotonically"
    np.testing.assert_array_equal(outcome.q[0], path[0])


def test_hard_limits_hold_exactly_when_targets_ask_for_more(planar3):
    """planar3 on a fixed base (a non-redundant arm) and targets from a path that leaves joint 3's
    range and jumps joint 1: with limits widened the solution follows the path out of the true
    limits; with the true limits it stays inside exactly (after the projection), limits active."""
    arm = dataclasses.replace(planar3, base_dofs=np.zeros(3, dtype=bool))
    steps = 24
    path = reachable_path(arm, steps, amplitude=0.1)
    path[:, 2] = np.linspace(arm.q_neutral[2], arm.upper[2] + 0.3, steps + 1)
    path[12:, 0] += 0.6  # joint 1 jumps: far above its velocity limit
    targets = targets_of(arm, path, np.zeros(3))
    options = SqpOptions(max_iterations=30)
    relaxed = dataclasses.replace(arm, lower=arm.lower - 2.0, upper=arm.upper + 2.0,
                                  velocity_limit=arm.velocity_limit * 20)
    relaxed_problem = TrackingProblem(relaxed, targets, 1 / FPS, q_start=path[0], weights=PRECISE)
    loose = solve_sqp(relaxed_problem, np.zeros(3), options)
    loose_v = np.diff(loose.q, axis=0) * FPS
    assert np.any(loose.q > arm.upper + 0.1) and np.any(np.abs(loose_v) > arm.velocity_limit * 1.5)

    outcome = solve_sqp(TrackingProblem(arm, targets, 1 / FPS, q_start=path[0], weights=PRECISE), np.zeros(3), options)
    velocities = np.diff(outcome.q, axis=0) * FPS
    assert np.all(outcome.q >= arm.lower) and np.all(outcome.q <= arm.upper)
    assert np.all(np.abs(velocities) <= arm.velocity_limit * (1 + 1e-12))
    assert outcome.q[:, 2].max() == pytest.approx(arm.upper[2], abs=1e-4), "joint 3's limit should be active"
    assert np.max(np.abs(velocities[:, 0]) / arm.velocity_limit[0]) == pytest.approx(1.0, abs=1e-4)


def test_projection_satisfies_both_limits():
    rng = np.random.default_rng(0)
    lower, upper, vlim, dt = -np.ones(4), np.ones(4), np.full(4, 2.0), 0.1
    bound = MotionBound(lower, upper, vlim, None)
    q = rng.uniform(-3, 3, size=(50, 4))
    q[0] = 0.0
    projected = project_to_limits(q, dt, bound)
    assert np.all(projected >= lower) and np.all(projected <= upper)
    assert np.all(np.abs(np.diff(projected, axis=0)) <= vlim * dt + 1e-15)
    inside = np.cumsum(np.full((5, 4), 0.1), axis=0) - 0.1  # a feasible path is unchanged
    np.testing.assert_allclose(project_to_limits(inside, dt, bound), inside)


def test_projection_keeps_the_acceleration_bound_from_rest():
    rng = np.random.default_rng(1)
    lower, upper, vlim, alim, dt = -np.ones(3), np.ones(3), np.full(3, 2.0), np.full(3, 5.0), 0.05
    q = rng.uniform(-3, 3, size=(80, 3))
    q[0] = 0.0
    projected = project_to_limits(q, dt, MotionBound(lower, upper, vlim, alim))
    velocity = np.vstack([np.zeros((1, 3)), np.diff(projected, axis=0) / dt])
    assert np.all(projected >= lower) and np.all(projected <= upper)
    assert np.all(np.abs(velocity) <= vlim + 1e-12)
    assert np.all(np.abs(np.diff(velocity, axis=0) / dt) <= alim * (1 + 1e-9))


def test_the_qp_keeps_the_panda_within_its_acceleration_bound(panda):
    """A path whose targets start at full speed: with the Panda's bound (published limits within
    the margins) the solution starts from rest and never changes velocity faster than the bound;
    with the model's limits alone it does."""
    path = reachable_path(panda, 20, amplitude=0.6)
    targets = targets_of(panda, path, np.zeros(3))
    options = SqpOptions(max_iterations=15)
    for bound, bounded in ((MotionBound.of(panda), True), (MotionBound.model(panda), False)):
        problem = TrackingProblem(panda, targets, 1 / FPS, q_start=path[0], weights=PRECISE, bound=bound)
        outcome = solve_sqp(problem, np.zeros(3), options)
        velocity = np.vstack([np.zeros((1, 7)), np.diff(outcome.q, axis=0) * FPS])
        ratio = np.max(np.abs(np.diff(velocity, axis=0) * FPS) / MotionBound.of(panda).acceleration)
        assert (ratio <= 1 + 1e-6) == bounded, f"acceleration / bound {ratio:.3f}"


def test_iteration_budget_and_bad_guess(planar3):
    path = reachable_path(planar3, 10)
    problem = TrackingProblem(planar3, targets_of(planar3, path, np.zeros(3)), 1 / FPS, q_start=path[0])
    outcome = solve_sqp(problem, np.array([0.3, 0.0, 0.0]), SqpOptions(max_iterations=2))
    assert outcome.iterations <= 2 and not outcome.converged
    assert outcome.base[1] == 0.0 and outcome.base[2] == 0.0, "planar3's base moves along x only"
    with pytest.raises(ValueError, match="base guess"):
        solve_sqp(problem, np.array([0.0, np.nan, 0.0]))
    with pytest.raises(ValueError, match="max_iterations"):
        SqpOptions(max_iterations=-1)


def test_solves_print_nothing(planar3, capfd):
    """OSQP 1.x prints a polishing notice on every solve with no active set, verbose or not
    (osqp/osqp#785): the solver silences it, so a long optimisation keeps the terminal readable."""
    path = reachable_path(planar3, 12, amplitude=0.05)
    targets = targets_of(planar3, path, np.zeros(3))
    solve_sqp(TrackingProblem(planar3, targets, 1 / FPS, q_start=path[0]), np.zeros(3), SqpOptions(max_iterations=5))
    print("after the solve")
    out = capfd.readouterr().out
    assert "Polishing" not in out
    assert out == "after the solve\n"


def test_posture_term_keeps_the_arm_near_its_rest_configuration(panda):
    """With w_p > 0 the optimum trades tracking for staying near q_0: it ends closer to q_0 than
    without the term, J holds the posture term's value, and the SQP still descends to it."""
    base = np.array([0.1, -0.2, 0.3])
    path = reachable_path(panda, 10, amplitude=0.3)
    targets = targets_of(panda, path, base)
    distance = {}
    for w_p in (0.0, 5.0):
        weights = TrackingWeights(1.0, 0.5, 0.01, posture=w_p)
        problem = TrackingProblem(panda, targets, 1 / FPS, q_start=path[0], weights=weights)
        outcome = solve_sqp(problem, base, SqpOptions(max_iterations=30))
        terms = problem.cost_terms(outcome.base, outcome.q)
        assert terms["posture"] == pytest.approx(0.5 * w_p * np.sum((outcome.q[1:] - path[0]) ** 2))
        assert outcome.cost == pytest.approx(terms["total"]) and outcome.cost <= outcome.cost_history[0]
        distance[w_p] = float(np.sum((outcome.q[1:] - path[0]) ** 2))
    assert distance[5.0] < 0.5 * distance[0.0]
