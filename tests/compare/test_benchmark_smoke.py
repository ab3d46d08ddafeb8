"""The benchmark script's solver runs on a short horizon: both solvers, the same problem, one report."""

from __future__ import annotations

import numpy as np
import pytest


def test_both_solvers_on_a_short_horizon(trajopt_problem, trajopt_benchmark, panda_on_base, video_demos_dir):
    pytest.importorskip("crocoddyl", reason='crocoddyl is optional: pip install -e ".[compare]"')
    full = trajopt_problem.load_targets(video_demos_dir / "spade_example_aligned.npz")
    targets = trajopt_problem.Targets("short", full.positions[:12], full.rotations[:12], full.fps)
    problem = trajopt_problem.make_problem(panda_on_base, targets)
    guesses = trajopt_problem.initial_base_guesses(panda_on_base, targets)[:2]
    robot = trajopt_benchmark.panda_with_problem_tool(panda_on_base)
    runs = {
        "crocoddyl": trajopt_benchmark.run_crocoddyl(problem, guesses, repeats=1),
        "toolimit": trajopt_benchmark.run_toolimit(targets, guesses, 1, robot, problem.dt),
    }
    reports = {name: trajopt_benchmark.solver_report(problem, run, with_static_ik=False) for name, run in runs.items()}
    for name, report in reports.items():
        assert report["q_trajectory"].shape == (13, 10) and report["u_trajectory"].shape == (12, 10), name
        # the layout obeys PROBLEM.md's dynamics q_{k+1} = q_k + B_k u_k
        q, u = report["q_trajectory"], report["u_trajectory"]
        np.testing.assert_allclose(q[1, :3], q[0, :3] + u[0, :3], atol=1e-12)
        np.testing.assert_allclose(q[1:, 3:], q[:-1, 3:] + problem.dt * u[:, 3:], atol=1e-9)
        assert report["velocity_violation_steps"] == 0, name
        assert report["cost"] == pytest.approx(report["solver_reported_cost"], rel=1e-6), name
    assert reports["toolimit"]["limit_violation_steps"] == 0
    # both find the same optimum of this short problem
    assert reports["toolimit"]["cost"] == pytest.approx(reports["crocoddyl"]["cost"], rel=1e-3)
