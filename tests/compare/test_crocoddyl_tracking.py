"""The Crocoddyl transcription: analytic derivatives, cost agreement, and PROBLEM.md's reference figures."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from toolimit.compare import evaluate_cost, pose_residual


@pytest.fixture(scope="module")
def crocoddyl_models():
    pytest.importorskip("crocoddyl", reason='crocoddyl is optional: pip install -e ".[compare]"')
    from toolimit.compare import crocoddyl_models

    return crocoddyl_models


@pytest.fixture(scope="module")
def short_problem(trajopt_problem, panda_on_base, video_demos_dir):
    """video1's first 6 targets: a short horizon for cheap checks."""
    targets = trajopt_problem.load_targets(video_demos_dir / "spade_video1_aligned.npz")
    short = trajopt_problem.Targets("short", targets.positions[:6], targets.rotations[:6], targets.fps)
    return trajopt_problem.make_problem(panda_on_base, short)


def _finite_difference(function, x, step=1e-6):
    return np.array([(function(x + step * e) - function(x - step * e)) / (2 * step) for e in np.eye(len(x))]).T


@pytest.mark.parametrize("node", [0, 2, 6])
def test_derivatives_match_finite_differences(crocoddyl_models, short_problem, node):
    model = crocoddyl_models.TrackingNodeModel(short_problem, node)
    data = model.createData()
    rng = np.random.default_rng(node)
    x = np.concatenate([[0.2, -0.1, 2.2], rng.uniform(short_problem.lower, short_problem.upper)])
    x[3 + 5] = short_problem.upper[5] + 0.05  # one joint outside its limits: the barrier is active
    u = rng.uniform(-1.0, 1.0, 10)
    terminal = node == short_problem.horizon

    def cost_of_x(x_):
        model.calc(data, x_, None if terminal else u)
        return np.array([data.cost])

    def cost_of_u(u_):
        model.calc(data, x, u_)
        return np.array([data.cost])

    def next_state(u_):
        model.calc(data, x, u_)
        return data.xnext.copy()

    model.calc(data, x, None if terminal else u)
    model.calcDiff(data, x, None if terminal else u)
    np.testing.assert_allclose(data.Lx, _finite_difference(cost_of_x, x)[0], atol=1e-6)
    if node > 0:  # Gauss-Newton Hessian: J^T J of the pose residual, plus w_lim where out of limits
        pinocchio_data = short_problem.model.createData()
        target = short_problem.target(node)
        jacobian = _finite_difference(lambda x_: pose_residual(short_problem, pinocchio_data, x_, target), x)
        expected = jacobian.T @ jacobian
        expected[3 + 5, 3 + 5] += short_problem.w_lim
        np.testing.assert_allclose(data.Lxx, expected, atol=1e-6)
    if not terminal:
        np.testing.assert_allclose(data.Lu, _finite_difference(cost_of_u, u)[0], atol=1e-6)
        np.testing.assert_allclose(data.Fu, _finite_difference(next_state, u), atol=1e-8)
        np.testing.assert_allclose(data.Fx, np.eye(10))
        base_cost = 0.0 if node == 0 else 1.0
        np.testing.assert_allclose(np.diag(data.Luu), [base_cost] * 3 + [short_problem.w_v] * 7)


def test_node0_places_the_base_and_later_nodes_freeze_it(crocoddyl_models, short_problem):
    x = np.concatenate([np.zeros(3), short_problem.q0[3:]])
    u = np.concatenate([[0.3, -0.2, 0.5], np.full(7, 0.1)])
    first, later = (crocoddyl_models.TrackingNodeModel(short_problem, k) for k in (0, 1))
    first_data, later_data = first.createData(), later.createData()
    first.calc(first_data, x, u)
    later.calc(later_data, x, u)
    np.testing.assert_allclose(first_data.xnext[:3], [0.3, -0.2, 0.5])
    np.testing.assert_array_equal(later_data.xnext[:3], x[:3])
    np.testing.assert_allclose(later_data.xnext[3:], x[3:] + short_problem.dt * 0.1)
    np.testing.assert_allclose(first.u_ub, [10, 10, 10, *short_problem.velocity_limit])


def test_crocoddyl_cost_of_a_rollout_equals_the_evaluator(crocoddyl_models, short_problem):
    rng = np.random.default_rng(3)
    x0 = np.concatenate([[0.1, 0.2, 0.3], short_problem.q0[3:]])
    us = [np.concatenate([[0.2, -0.1, 1.0], rng.uniform(-2, 2, 7)])]
    us += [np.concatenate([np.zeros(3), rng.uniform(-2, 2, 7)]) for _ in range(short_problem.horizon - 1)]
    shooting = crocoddyl_models.shooting_problem(short_problem, x0)
    xs = shooting.rollout(us)
    solver_cost = shooting.calc(xs, us)
    assert solver_cost == pytest.approx(evaluate_cost(short_problem, np.array(xs)).total, rel=1e-12)


def test_reproduces_the_reference_solution(crocoddyl_models, trajopt_problem, panda_on_base, video_demos_dir):
    """PROBLEM.md: video1's best guess gives J = 6.357955 in 22 iterations at base (0.1881, -0.1080, 2.2144)."""
    from toolimit.compare.crocoddyl_tracking import solve_with_crocoddyl

    targets = trajopt_problem.load_targets(video_demos_dir / "spade_video1_aligned.npz")
    problem = trajopt_problem.make_problem(panda_on_base, targets)
    guess = trajopt_problem.initial_base_guesses(panda_on_base, targets)[6]
    solution = solve_with_crocoddyl(problem, guess)
    assert solution.converged
    assert solution.cost == pytest.approx(6.357955, abs=1e-6)
    assert solution.iterations == pytest.approx(22, abs=2)
    np.testing.assert_allclose(solution.q_trajectory[1, :3], [0.1881, -0.1080, 2.2144], atol=1e-4)
    assert np.all(solution.q_trajectory[1:, :3] == solution.q_trajectory[1, :3])  # base frozen exactly
    assert evaluate_cost(problem, solution.q_trajectory).total == pytest.approx(solution.cost, rel=1e-9)
    assert np.all(np.abs(solution.u_trajectory[:, 3:]) <= problem.velocity_limit)
    # PROBLEM.md's tight-tolerance optimum: 6.3579449004 in 36 iterations
    tight = solve_with_crocoddyl(problem, guess, th_stop=1e-10)
    assert tight.cost == pytest.approx(6.3579449004, abs=2e-10)
    np.testing.assert_allclose(tight.q_trajectory[1, :3], [0.18796, -0.10855, 2.21463], atol=1e-5)


def test_missing_crocoddyl_gives_the_install_command(monkeypatch):
    from toolimit.compare import crocoddyl_tracking

    monkeypatch.setitem(sys.modules, "crocoddyl", None)
    monkeypatch.delitem(sys.modules, "toolimit.compare.crocoddyl_models", raising=False)
    with pytest.raises(ImportError, match=r'pip install -e "\.\[compare\]"'):
        crocoddyl_tracking.solve_with_crocoddyl(None, np.zeros(3))
