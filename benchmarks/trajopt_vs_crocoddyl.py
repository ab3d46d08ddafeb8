"""Benchmark: toolimit's sequential-QP tracking vs Crocoddyl's BoxFDDP on PROBLEM.md's reference problem.

Both solvers get the same model (Panda + spade_tip on a PX-PY-RZ base), the same targets (the two
real spade trajectories), the same 8 base guesses, and are scored by the same evaluator of J
(:func:`toolimit.compare.evaluate_cost`, barrier term included) and the same metrics
(benchmarks/trajopt_problem.py), never by a solver's own number. Writes
``benchmarks/results/trajopt_<trajectory>.json`` and prints J and time ratios. A variant runs
toolimit's automatic time scale (``choose_time_scale``) and Crocoddyl on the same slowed-down problem.

Run (about 25 s of CPU per trajectory; about 2 minutes in all on a loaded 2-core machine)::

    python benchmarks/trajopt_vs_crocoddyl.py [--trajectory spade_video1_aligned] [--repeats 5]
        [--skip-static-ik] [--skip-time-scale-auto]

Needs crocoddyl (``pip install -e ".[compare]"``) and the real data in ../shared (or --data DIR).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import platform
import statistics
import sys
import time
from dataclasses import dataclass
from datetime import datetime, timezone
from importlib.metadata import version
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # trajopt_problem beside this script

from toolimit.artifacts import save_json  # noqa: E402
from toolimit.compare.crocoddyl_tracking import solve_with_crocoddyl  # noqa: E402
from toolimit.robots import make_robot  # noqa: E402
from toolimit.robots.motion_bound import MotionBound  # noqa: E402
from toolimit.trajopt import (  # noqa: E402
    PoseTargets,
    TrackingProblem,
    TrackingWeights,
    TrackOptions,
    choose_time_scale,
    solve_sqp,
    track,
)
from toolimit.trajopt.initial_guess import ik_rollout  # noqa: E402

import trajopt_problem as tp  # noqa: E402

REPO_ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = Path(os.environ.get("TOOLIMIT_SHARED", REPO_ROOT.parent / "shared")) / "data" / "video_demos"
DEFAULT_OUT = REPO_ROOT / "benchmarks" / "results"


@dataclass(frozen=True)
class SolverRun:
    """One solver's answer on one trajectory, in PROBLEM.md's layout.

    q_trajectory (T+1, 10) = [bx, by, byaw, q1..q7] with q_0 = [best base guess, q0_arm] (as
    Crocoddyl's xs[0]); u_trajectory (T, 10) = [db_k, v_{k+1}] (db_0 = base - guess, then 0).
    """

    q_trajectory: np.ndarray
    u_trajectory: np.ndarray
    solver_cost: float
    iterations: int
    converged: bool
    solve_times_s: list[float]
    multistart_total_time_s: float
    start_costs: list[float]
    best_start: int


def _problem_layout(base: np.ndarray, guess: np.ndarray, q_arm: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """q_trajectory and u_trajectory of PROBLEM.md from a base (3,), its guess (3,) and arm q (T+1, 7)."""
    horizon = len(q_arm) - 1
    q_trajectory = np.hstack([np.tile(base, (horizon + 1, 1)), q_arm])
    q_trajectory[0, :3] = guess
    u_trajectory = np.hstack([np.zeros((horizon, 3)), np.diff(q_arm, axis=0) / dt])
    u_trajectory[0, :3] = base - guess
    return q_trajectory, u_trajectory


def run_crocoddyl(problem, guesses: np.ndarray, repeats: int) -> SolverRun:
    """8-guess multi-start (build + solve timed), then ``repeats`` (>= 0) timed solves of the best guess."""
    started = time.perf_counter()
    solutions = [solve_with_crocoddyl(problem, guess) for guess in guesses]
    multistart = time.perf_counter() - started
    costs = [solution.cost for solution in solutions]
    best_start = int(np.argmin(costs))
    best = solutions[best_start]
    times = [solve_with_crocoddyl(problem, guesses[best_start]).solve_time_s for _ in range(repeats)]
    return SolverRun(best.q_trajectory, best.u_trajectory, best.cost, best.iterations, best.converged, times,
                     multistart, costs, best_start)


def panda_with_problem_tool(robot_model: tp.PandaOnBase):
    """toolimit's Panda holding the spade as PROBLEM.md places it (relative to joint 7), base on the floor."""
    link8 = robot_model.model.frames[robot_model.model.getFrameId("panda_link8")].placement
    return make_robot("panda", tool="spade", tool_placement=link8 * tp.tool_placement(), base_height=0.0)


#: PROBLEM.md's trajectory initialisation (the arm holds q0 at every node), as Crocoddyl's.
HOLD = ("hold",)
#: toolimit's CLI default: every base guess from the held q0 AND from a differential-IK rollout.
HOLD_AND_ROLLOUT = ("hold", "rollout")


def toolimit_options(targets: tp.Targets, dt: float, robot, initialisations: tuple[str, ...] = HOLD) -> TrackOptions:
    """PROBLEM.md's weights, start configuration and time step for toolimit's ``track``, within the
    model's position and velocity limits alone: the problem Crocoddyl solves (no acceleration bound)."""
    weights = TrackingWeights(position=tp.POSE_WEIGHTS[0], rotation=tp.POSE_WEIGHTS[3], velocity=tp.W_V)
    return TrackOptions(weights=weights, q_start=tp.Q0_ARM, time_scale=dt * targets.fps,
                        initialisations=initialisations, bound=MotionBound.model(robot))


def run_toolimit(targets: tp.Targets, guesses: np.ndarray, repeats: int, robot, dt: float,
                 initialisations: tuple[str, ...] = HOLD) -> SolverRun:
    """toolimit's multi-start ``track`` over the same guesses, then ``repeats`` timed SQP solves of the best
    (with its joint initialisation, the rollout included in the time when it won)."""
    pose_targets = PoseTargets(targets.positions, targets.rotations, targets.fps)
    options = toolimit_options(targets, dt, robot, initialisations)
    weights = options.weights
    started = time.perf_counter()
    result = track(robot, pose_targets, options, guesses=guesses)
    multistart = time.perf_counter() - started
    stats = result.statistics
    best_start = stats.start_index
    problem = TrackingProblem(robot, pose_targets, dt, tp.Q0_ARM, weights, bound=options.bound)
    times = []
    rollout = stats.initialisation == "rollout"
    for _ in range(repeats):
        begun = time.perf_counter()
        q_guess = ik_rollout(problem, guesses[best_start]) if rollout else None
        solve_sqp(problem, guesses[best_start], options.sqp, q_guess=q_guess)
        times.append(time.perf_counter() - begun)
    q_trajectory, u_trajectory = _problem_layout(result.base, guesses[best_start], result.q, dt)
    return SolverRun(q_trajectory, u_trajectory, stats.cost, stats.iterations,
                     stats.converged, times, multistart, list(stats.start_costs), best_start)


def solver_report(problem, run: SolverRun, with_static_ik: bool) -> dict:
    """PROBLEM.md's metrics of a run, J from the shared evaluator."""
    metrics = tp.trajectory_metrics(problem, run.q_trajectory, with_static_ik=with_static_ik)
    base = np.array(metrics["base"])
    base[2] = (base[2] + np.pi) % (2 * np.pi) - np.pi
    return {
        "cost": metrics.pop("cost"),
        "cost_terms": metrics.pop("cost_terms"),
        "solver_reported_cost": run.solver_cost,
        "iterations": run.iterations,
        "converged": run.converged,
        "solve_time_median_s": statistics.median(run.solve_times_s),
        "solve_times_s": run.solve_times_s,
        "multistart_total_time_s": run.multistart_total_time_s,
        "best_start": run.best_start,
        "start_costs": run.start_costs,
        **metrics,
        "base": base.tolist(),
        "q_trajectory": run.q_trajectory,
        "u_trajectory": run.u_trajectory,
    }


def time_scale_variant(robot_model: tp.PandaOnBase, targets: tp.Targets, robot) -> dict:
    """toolimit's ``--time-scale auto`` (choose_time_scale, both joint initialisations as the CLI's
    default), scored at its time step, with Crocoddyl solving the same slowed-down problem from the
    same 8 guesses (held q0) for a pair-wise J."""
    pose_targets = PoseTargets(targets.positions, targets.rotations, targets.fps)
    started = time.perf_counter()
    result = choose_time_scale(robot, pose_targets, toolimit_options(targets, tp.DT, robot, HOLD_AND_ROLLOUT))
    elapsed = time.perf_counter() - started
    dt = result.time_scale / targets.fps
    problem = tp.make_problem(robot_model, targets, dt=dt)
    guesses = tp.initial_base_guesses(robot_model, targets)
    start = result.statistics.start_index
    q_trajectory, _ = _problem_layout(result.base, guesses[start], result.q, dt)
    toolimit_metrics = tp.trajectory_metrics(problem, q_trajectory, with_static_ik=False)
    crocoddyl_run = run_crocoddyl(problem, guesses, repeats=0)
    crocoddyl_metrics = tp.trajectory_metrics(problem, crocoddyl_run.q_trajectory, with_static_ik=False)
    keep = ("cost", "cost_terms", "base", "position_error_m", "rotation_error_rad", "steps_pos_err_gt_1cm",
            "limit_violation_steps", "limit_violation_max_rad", "vel_ratio_max", "velocity_violation_steps")
    return {
        "time_scale": result.time_scale,
        "dt": dt,
        "search": result.statistics.time_scale_search.to_json(),
        "toolimit": {**{key: toolimit_metrics[key] for key in keep}, "total_time_s": elapsed},
        "crocoddyl_same_time_scale": {**{key: crocoddyl_metrics[key] for key in keep},
                                      "multistart_total_time_s": crocoddyl_run.multistart_total_time_s},
        "cost_ratio_minus_1": toolimit_metrics["cost"] / crocoddyl_metrics["cost"] - 1.0,
    }


def code_fingerprint() -> str:
    """SHA-256 (first 16 hex digits) of the solvers' and evaluator's source, to trace which code made a result."""
    digest = hashlib.sha256()
    for folder in ("toolimit/trajopt", "toolimit/compare", "toolimit/robots"):
        for path in sorted((REPO_ROOT / folder).glob("*.py")):
            digest.update(path.name.encode() + path.read_bytes())
    digest.update((REPO_ROOT / "benchmarks" / "trajopt_problem.py").read_bytes())
    return digest.hexdigest()[:16]


def benchmark(name: str, data_dir: Path, repeats: int, with_static_ik: bool, with_time_scale: bool) -> dict:
    load_before = os.getloadavg()[0]
    cpu_before = time.process_time()
    robot_model = tp.build_panda_on_base()
    targets = tp.load_targets(data_dir / f"{name}.npz")
    problem = tp.make_problem(robot_model, targets)
    guesses = tp.initial_base_guesses(robot_model, targets)
    print(f"[{name}] Crocoddyl BoxFDDP: 8 starts + {repeats} timed solves", flush=True)
    crocoddyl_run = run_crocoddyl(problem, guesses, repeats)
    print(f"[{name}] toolimit SQP: 8 starts + {repeats} timed solves", flush=True)
    robot = panda_with_problem_tool(robot_model)
    toolimit_run = run_toolimit(targets, guesses, repeats, robot, problem.dt)
    print(f"[{name}] toolimit SQP with the CLI's default initialisations (hold + rollout)", flush=True)
    both_run = run_toolimit(targets, guesses, 0, robot, problem.dt, HOLD_AND_ROLLOUT)
    print(f"[{name}] metrics (static IK: {with_static_ik})", flush=True)
    reports = {"crocoddyl": solver_report(problem, crocoddyl_run, with_static_ik),
               "toolimit": solver_report(problem, toolimit_run, with_static_ik)}
    both = tp.trajectory_metrics(problem, both_run.q_trajectory, with_static_ik=False)
    keep = ("cost", "cost_terms", "base", "position_error_m", "limit_violation_steps", "velocity_violation_steps")
    reports["toolimit_hold_and_rollout"] = {**{key: both[key] for key in keep},
                                            "multistart_total_time_s": both_run.multistart_total_time_s,
                                            "start_costs": both_run.start_costs}
    croc, tool = reports["crocoddyl"], reports["toolimit"]
    comparison = {
        "cost_ratio_minus_1": tool["cost"] / croc["cost"] - 1.0,
        "solve_time_ratio": tool["solve_time_median_s"] / croc["solve_time_median_s"],
        "multistart_time_ratio": tool["multistart_total_time_s"] / croc["multistart_total_time_s"],
    }
    variant = None
    if with_time_scale:
        print(f"[{name}] toolimit --time-scale auto, and Crocoddyl at the scale it picks", flush=True)
        variant = time_scale_variant(robot_model, targets, robot)
    return {
        "trajectory": name,
        "problem": {"spec": "../shared/benchmarks/trajopt/PROBLEM.md", "horizon": problem.horizon, "dt": problem.dt,
                    "pose_weights": tp.POSE_WEIGHTS, "w_v": tp.W_V, "w_lim": tp.W_LIM, "q0_arm": tp.Q0_ARM,
                    "base_guesses": guesses,
                    "tolerances": {"limit_violation_rad": tp.LIMIT_TOLERANCE,
                                   "velocity_at_limit_ratio": tp.VELOCITY_AT_LIMIT,
                                   "velocity_violation_ratio_excess": tp.VELOCITY_TOLERANCE}},
        "timing_note": ("crocoddyl: solver.solve only (Python action models); toolimit: the whole solve_sqp call "
                        "(QP setup, linearisations, OSQP); both single-threaded, same process, shared machine"),
        "environment": {"date_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
                        "code_fingerprint": code_fingerprint(),
                        "load_average_1min": [load_before, os.getloadavg()[0]],
                        "process_cpu_time_s": time.process_time() - cpu_before,
                        "python": platform.python_version(), "machine": platform.machine(), "cpus": os.cpu_count(),
                        **{package: version(package) for package in ("crocoddyl", "pin", "osqp", "numpy", "scipy")}},
        "comparison": comparison,
        **reports,
        "time_scale_auto": variant,
    }


def print_summary(result: dict) -> None:
    croc, tool, comparison = result["crocoddyl"], result["toolimit"], result["comparison"]
    print(f"\n== {result['trajectory']} ==")
    print(f"{'':28}{'crocoddyl':>14}{'toolimit':>14}")
    rows = [
        ("J", "cost", "{:.6f}"),
        ("  pose", ("cost_terms", "pose"), "{:.4f}"),
        ("  velocity", ("cost_terms", "velocity"), "{:.4f}"),
        ("  joint limits", ("cost_terms", "joint_limits"), "{:.4f}"),
        ("iterations", "iterations", "{}"),
        ("converged", "converged", "{}"),
        ("solve time median (s)", "solve_time_median_s", "{:.3f}"),
        ("multi-start total (s)", "multistart_total_time_s", "{:.3f}"),
        ("pos err mean (cm)", ("position_error_m", "mean"), "{:.4g}", 100.0),
        ("pos err max (cm)", ("position_error_m", "max"), "{:.4g}", 100.0),
        ("rot err mean (rad)", ("rotation_error_rad", "mean"), "{:.3f}"),
        ("limit violation steps", "limit_violation_steps", "{}"),
        ("limit violation max (rad)", "limit_violation_max_rad", "{:.4f}"),
        ("max |v|/vlim", "vel_ratio_max", "{:.4f}"),
        ("steps at velocity limit", "steps_at_velocity_limit", "{}"),
        ("velocity violation steps", "velocity_violation_steps", "{}"),
        ("unreachable (IK position)", "unreachable_steps_static_ik_position", "{}"),
        ("unreachable (IK pose)", "unreachable_steps_static_ik_pose", "{}"),
    ]
    for label, key, fmt, *scale in rows:
        cells = []
        for report in (croc, tool):
            value = report
            for part in (key if isinstance(key, tuple) else (key,)):
                value = value.get(part, "-") if isinstance(value, dict) else "-"
            if scale and value != "-":
                value = value * scale[0]
            cells.append(fmt.format(value) if value != "-" else "-")
        print(f"{label:28}{cells[0]:>14}{cells[1]:>14}")
    print(f"base crocoddyl {np.round(croc['base'], 4).tolist()}, toolimit {np.round(tool['base'], 4).tolist()}")
    print(f"J_toolimit / J_crocoddyl - 1 = {comparison['cost_ratio_minus_1']:+.3e}; "
          f"solve time ratio {comparison['solve_time_ratio']:.2f}; "
          f"multi-start time ratio {comparison['multistart_time_ratio']:.2f}")
    extra = result["toolimit_hold_and_rollout"]
    print(f"toolimit with hold + rollout initialisations (CLI default): J {extra['cost']:.6f}, "
          f"multi-start {extra['multistart_total_time_s']:.2f} s")
    environment = result["environment"]
    print(f"(timings on a shared machine: 1-min load average {environment['load_average_1min'][0]:.1f} -> "
          f"{environment['load_average_1min'][1]:.1f}, {environment['cpus']} CPUs; "
          f"process CPU time {environment['process_cpu_time_s']:.1f} s)")
    variant = result["time_scale_auto"]
    if variant is not None:
        tool, croc = variant["toolimit"], variant["crocoddyl_same_time_scale"]
        print(f"--time-scale auto picked {variant['time_scale']:g} (dt {variant['dt']:.4f} s): "
              f"J toolimit {tool['cost']:.6f}, "
              f"Crocoddyl {croc['cost']:.6f} ({variant['cost_ratio_minus_1']:+.2e}); position error mean/median "
              f"{100 * tool['position_error_m']['mean']:.2f} / {100 * tool['position_error_m']['median']:.2f} cm; "
              f"limit / velocity violation steps {tool['limit_violation_steps']} / {tool['velocity_violation_steps']}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trajectory", choices=(*tp.TRAJECTORIES, "all"), default="all")
    parser.add_argument("--repeats", type=int, default=5, help="timed solves of the best guess (median reported)")
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA, help="folder of the real spade trajectories")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="folder for trajopt_<trajectory>.json")
    parser.add_argument("--skip-static-ik", action="store_true", help="skip the static-IK reachability counts")
    parser.add_argument("--skip-time-scale-auto", action="store_true",
                        help="skip the variant with toolimit's automatic time scale")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    names = tp.TRAJECTORIES if args.trajectory == "all" else (args.trajectory,)
    for name in names:
        if not (args.data / f"{name}.npz").is_file():
            parser.error(f"{args.data / (name + '.npz')} not found (set --data or TOOLIMIT_SHARED)")
    for name in names:
        result = benchmark(name, args.data, args.repeats, not args.skip_static_ik, not args.skip_time_scale_auto)
        save_json(args.out / f"trajopt_{name}.json", result)
        print_summary(result)
        print(f"wrote {args.out / f'trajopt_{name}.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
