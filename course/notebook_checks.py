"""Instant feedback for the exercises inside notebooks 01-06: each ``check_*`` calls the student's
function on the notebook's own data, compares it with the library's answer, prints one line per
case (what was expected, what came back) and draws the student's result beside the reference's
(``toolimit.viz`` SVG plots). It returns True when every case passes.

This is feedback, not grading: it runs in the notebook's process. The graded exercises are the
files in ``exercises/`` (``grade.py``); each notebook says which one holds the same function.
A function that still raises NotImplementedError gets "not written yet" and the reference's
picture alone, so a student's notebook runs from top to bottom before they start.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from IPython.display import HTML, display

from toolimit.viz.svg_plot import Series, line_plot_svg

PASSED, FAILED = "exercise passed", "not yet"
YOURS, REFERENCE = "#D55E00", "#0072B2"


def _call(function: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[Any, str | None]:
    """(value, None), or (None, why there is no value)."""
    try:
        return function(*args, **kwargs), None
    except NotImplementedError:
        return None, "not written yet (it raises NotImplementedError)"
    except Exception as error:  # noqa: BLE001 - the student's code: report it, do not stop the notebook
        return None, f"raised {type(error).__name__}: {error}"


def _report(title: str, cases: list[tuple[bool, str]], yours: str | None, reference: str) -> bool:
    """Print the verdict and the cases; show the two pictures side by side. True when all passed."""
    passed = bool(cases) and all(ok for ok, _ in cases)
    print(f"{title}: {PASSED if passed else FAILED}")
    for ok, text in cases:
        print(("  ok   " if ok else "  FAIL ") + text)
    panels = [("yours", yours), ("reference", reference)] if yours is not None else [("reference", reference)]
    cells = "".join(
        f'<div style="flex:1;min-width:320px"><b>{name}</b><br>{svg}</div>' for name, svg in panels if svg is not None
    )
    display(HTML(f'<div style="display:flex;gap:12px;flex-wrap:wrap">{cells}</div>'))
    return passed


def _array(value: Any) -> np.ndarray | None:
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None


# --- 01: velocity keypoints -----------------------------------------------------------------------
def check_velocity_keypoints(student: Callable[..., Any], demo: Any) -> bool:
    """Notebook 01: ``student(demo, fraction)`` against ``toolimit.align.keypoints.velocity_keypoints``."""
    from toolimit.align.keypoints import velocity_keypoints

    speed, times = demo.speed(), demo.times
    cases, shown = [], None
    for fraction in (0.05, 0.1, 0.3):
        expected = velocity_keypoints(demo, fraction)
        value, problem = _call(student, demo, fraction)
        frames = _array(value)
        if problem is None and (frames is None or frames.ndim != 1 or not np.all(frames == np.round(frames))):
            problem = f"expected a 1-D array of integer frame indices, got {value!r:.80}"
        if problem is None and (frames.min(initial=0) < 0 or frames.max(initial=0) >= demo.n_frames):
            problem = f"frames must lie in 0..{demo.n_frames - 1}, got {frames.astype(int).tolist()}"
        if problem is not None:
            cases.append((False, f"fraction {fraction}: {problem}"))
            continue
        frames = frames.astype(int)
        shown = frames if fraction == 0.05 else shown
        missing, extra = np.setdiff1d(expected, frames), np.setdiff1d(frames, expected)
        text = f"fraction {fraction}: {len(expected)} keypoints expected"
        if missing.size or extra.size:
            text += f"; missing {missing.tolist()[:8]}, not keypoints {extra.tolist()[:8]}"
        cases.append((not missing.size and not extra.size, text))

    def picture(frames: np.ndarray, colour: str) -> str:
        series = [
            Series("tool speed", times, speed, colour="#999999"),
            Series("keypoints", times[frames], speed[frames], line=False, markers=True, colour=colour),
        ]
        return line_plot_svg(series, "keypoints, fraction 0.05", "time (s)", "speed (m/s)", width=420, height=260)

    reference = picture(velocity_keypoints(demo, 0.05), REFERENCE)
    return _report("velocity keypoints", cases, None if shown is None else picture(shown, YOURS), reference)


# --- 02: the element sampler ----------------------------------------------------------------------
def check_element_sampling(
    student: Callable[..., Any], keypoints: np.ndarray, covariance: np.ndarray, min_distance: float
) -> bool:
    """Notebook 02: ``student(keypoints, n_elements, covariance, min_distance, rng)`` against
    ``toolimit.align.sampler.sample_element_positions``: 300 single draws (where they fall) and 20
    draws of 4 elements (their pairwise distances)."""
    from scipy.spatial.distance import pdist

    from toolimit.align.sampler import sample_element_positions

    def draws(sample: Callable[..., Any]) -> tuple[np.ndarray | None, str | None]:
        points = []
        for draw in range(300):
            value, problem = _call(sample, keypoints, 1, covariance, 0.0, np.random.default_rng([2, draw]))
            array = _array(value)
            if problem is None and (array is None or array.shape != (1, 3)):
                problem = f"one element: expected a (1, 3) array, got {value!r:.80}"
            if problem is not None:
                return None, problem
            points.append(array[0])
        return np.array(points), None

    expected, _ = draws(sample_element_positions)
    assert expected is not None
    got, problem = draws(student)
    cases = []
    if problem is not None:
        cases.append((False, problem))
    else:
        spread = np.sqrt(np.diag(covariance)).max()
        shift = np.abs(got.mean(0) - expected.mean(0)).max()
        cases.append(
            (shift < 0.5 * spread, f"mean of 300 draws within {0.5 * spread:.3f} m of the library's: {shift:.3f} m")
        )
        ratio = got.std(0)[[0, 2]] / np.maximum(expected.std(0)[[0, 2]], 1e-12)
        cases.append(
            (
                np.all(np.abs(ratio - 1) < 0.3),
                f"spread in x and z within 30 % of the library's: {np.round(ratio, 2).tolist()}",
            )
        )
        closest = []
        for draw in range(20):
            value, problem = _call(student, keypoints, 4, covariance, min_distance, np.random.default_rng([3, draw]))
            array = _array(value)
            if problem is not None or (value is not None and (array is None or array.shape != (4, 3))):
                cases.append((False, problem or f"four elements: expected a (4, 3) array or None, got {value!r:.80}"))
                break
            if value is not None:
                closest.append(pdist(array).min())
        else:
            ok = bool(closest) and min(closest) >= min_distance - 1e-12
            cases.append(
                (
                    ok,
                    f"4 elements: pairs >= min_distance {min_distance:.3f} m (closest {min(closest, default=0):.3f} m)",
                )
            )

    def picture(points: np.ndarray, colour: str) -> str:
        series = [
            Series("keypoints", keypoints[:, 0], keypoints[:, 2], line=False, markers=True, colour="#000000"),
            Series("elements", points[:, 0], points[:, 2], line=False, markers=True, colour=colour),
        ]
        return line_plot_svg(series, "300 single draws", "x (m)", "z (m)", width=420, height=300, equal_aspect=True)

    return _report("element sampler", cases, None if got is None else picture(got, YOURS), picture(expected, REFERENCE))


# --- 03: one differential-IK step -----------------------------------------------------------------
def _reference_diff_ik_step() -> Callable[..., np.ndarray]:
    """The QP of exercise 03 solved by OSQP with the library's Jacobian (the grader's own formula)."""
    import sys
    from pathlib import Path

    graders = str(Path(__file__).resolve().parent / "graders")
    sys.path.insert(0, graders)
    try:
        from test_ex03_diff_ik_step import Case, expected_velocity
    finally:
        sys.path.remove(graders)

    def step(robot, q, target_position, target_rotation, dt, pose_weights, velocity_weight, base):  # type: ignore[no-untyped-def]
        return expected_velocity(
            robot, Case("", q, target_position, target_rotation, dt, pose_weights, velocity_weight, base)
        )

    return step


def check_diff_ik_step(
    student: Callable[..., Any], robot: Any, targets: Any, base: np.ndarray, steps: int = 40
) -> bool:
    """Notebook 03: track the first ``steps`` tool targets with ``student``'s step and with the
    reference's, from the robot's neutral configuration; compare the joint velocities and the tool
    position error along the way (the picture)."""
    reference_step = _reference_diff_ik_step()
    dt = 1.0 / float(targets.fps)
    weights, velocity_weight = np.array([1.0, 1.0, 1.0, 0.3, 0.3, 0.3]), 1e-3
    n = min(steps, len(targets.positions))

    def track(step: Callable[..., Any]) -> tuple[np.ndarray | None, str | None, list[np.ndarray]]:
        q = np.clip(robot.q_neutral.copy(), robot.lower, robot.upper)
        errors, velocities = [], []
        for t in range(n):
            value, problem = _call(
                step, robot, q.copy(), targets.positions[t], targets.rotations[t], dt, weights, velocity_weight, base
            )
            v = _array(value)
            if problem is None and (v is None or v.shape != q.shape or not np.all(np.isfinite(v))):
                problem = f"step {t}: expected a ({len(q)},) array of joint velocities in rad/s, got {value!r:.80}"
            if problem is not None:
                return None, problem, velocities
            velocities.append(v)
            q = q + v * dt
            errors.append(np.linalg.norm(robot.tool_placement_world(q, base).translation - targets.positions[t]))
        return np.array(errors), None, velocities

    expected, _, expected_velocities = track(reference_step)
    got, problem, velocities = track(student)
    cases = []
    if problem is not None:
        cases.append((False, problem))
    else:
        gap = max(np.abs(a - b).max() for a, b in zip(velocities, expected_velocities))
        cases.append((gap < 1e-3, f"{n} steps: largest joint-velocity difference {gap:.2e} rad/s (tolerance 1e-3)"))
        cases.append(
            (
                got[-1] < expected[-1] + 1e-3,
                f"tool error after {n} steps {got[-1]:.4f} m (reference {expected[-1]:.4f} m)",
            )
        )

    def picture(errors: np.ndarray, colour: str) -> str:
        times = np.arange(len(errors)) * dt
        return line_plot_svg(
            [Series("tool position error", times, errors, colour=colour)],
            f"tracking the first {n} targets",
            "time (s)",
            "error (m)",
            width=420,
            height=260,
        )

    yours = None if got is None else picture(got, YOURS)
    return _report("differential-IK step", cases, yours, picture(expected, REFERENCE))


# --- 04: the cloning loss -------------------------------------------------------------------------
def check_cloning_loss(
    student: Callable[..., Any], make_policy: Callable[[], Any], observations: Any, actions: Any, steps: int = 150
) -> bool:
    """Notebook 04: ``student(policy, observations, actions)`` equal to the MSE of the policy's
    mean action, and ``steps`` Adam steps on it fitting the data as the reference's do (the picture:
    both loss curves). ``make_policy()`` gives a fresh policy, the same one each call."""
    import torch

    def reference(policy: Any) -> Any:
        return torch.mean((policy.get_distribution(observations).distribution.mean - actions) ** 2)

    def fit(loss: Callable[..., Any]) -> tuple[list[float] | None, str | None]:
        policy = make_policy()
        optimiser = torch.optim.Adam(policy.parameters(), lr=1e-3)
        curve = []
        for step in range(steps):
            value, problem = _call(loss, policy, observations, actions)
            if problem is None and not (isinstance(value, torch.Tensor) and value.dim() == 0 and value.requires_grad):
                problem = f"step {step}: expected a scalar tensor that requires grad, got {value!r:.80}"
            if problem is not None:
                return None, problem
            curve.append(float(reference(policy)))
            optimiser.zero_grad()
            value.backward()
            optimiser.step()
        return curve, None

    cases = []
    policy = make_policy()
    value, problem = _call(student, policy, observations, actions)
    expected = float(reference(policy))
    if problem is None and not isinstance(value, torch.Tensor):
        problem = f"expected a scalar tensor, got {value!r:.80}"
    cases.append(
        (
            problem is None and abs(float(value) - expected) <= 1e-5 * max(1.0, expected),
            problem or f"loss {float(value):.6f}, expected {expected:.6f}",
        )
    )
    curve, fit_problem = fit(student) if problem is None else (None, problem)
    expected_curve, _ = fit(lambda policy, o, a: reference(policy))
    assert expected_curve is not None
    if curve is not None:
        cases.append(
            (
                curve[-1] <= 1.05 * expected_curve[-1] + 1e-6,
                f"after {steps} Adam steps: {curve[-1]:.5f} (reference {expected_curve[-1]:.5f})",
            )
        )

    def picture(losses: list[float], colour: str) -> str:
        return line_plot_svg(
            [Series("mean squared error of the mean action", np.arange(len(losses)), losses, colour=colour)],
            "fitting with the loss",
            "Adam step",
            "MSE",
            width=420,
            height=260,
            log_y=True,
        )

    return _report(
        "cloning loss", cases, None if curve is None else picture(curve, YOURS), picture(expected_curve, REFERENCE)
    )


# --- 05: generalised advantage estimation ---------------------------------------------------------
def check_gae(student: Callable[..., Any], gamma: float = 0.99, gae_lambda: float = 0.95, seed: int = 0) -> bool:
    """Notebook 05: ``student(rewards, values, episode_starts, last_values, dones, gamma, gae_lambda)``
    against stable-baselines3's ``RolloutBuffer.compute_returns_and_advantage`` on a seeded rollout
    of 2 environments x 40 steps with episode ends (the picture: environment 0's advantages)."""
    import gymnasium as gym
    import torch
    from stable_baselines3.common.buffers import RolloutBuffer

    rng = np.random.default_rng(seed)
    steps, envs = 40, 2
    rewards = rng.normal(size=(steps, envs)).astype(np.float32)
    values = rng.normal(size=(steps, envs)).astype(np.float32)
    starts = (rng.random((steps, envs)) < 0.1).astype(np.float32)
    starts[0] = 1.0
    last_values, dones = rng.normal(size=envs).astype(np.float32), (rng.random(envs) < 0.5).astype(np.float32)
    space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
    buffer = RolloutBuffer(steps, space, space, gamma=gamma, gae_lambda=gae_lambda, n_envs=envs)
    for t in range(steps):
        buffer.add(
            np.zeros((envs, 1)), np.zeros((envs, 1)), rewards[t], starts[t], torch.tensor(values[t]), torch.zeros(envs)
        )
    buffer.compute_returns_and_advantage(torch.tensor(last_values), dones)
    expected = buffer.advantages
    value, problem = _call(student, rewards, values, starts, last_values, dones, gamma, gae_lambda)
    got = None
    if problem is None:
        if not (isinstance(value, tuple) and len(value) == 2):
            problem = f"expected a tuple (advantages, returns), got {value!r:.80}"
        else:
            got = _array(value[0])
            if got is None or got.shape != expected.shape:
                problem, got = f"advantages: expected shape {expected.shape}, got {value[0]!r:.80}", None
    cases = []
    if problem is not None:
        cases.append((False, problem))
    else:
        wrong = np.flatnonzero(np.abs(got - expected).max(axis=1) > 1e-4)
        text = "advantages equal to SB3's" if not wrong.size else f"first wrong step going backwards: t = {wrong.max()}"
        cases.append((not wrong.size, text))
        returns = _array(value[1])
        ok = (
            returns is not None
            and returns.shape == expected.shape
            and np.allclose(returns, expected + values, atol=1e-4)
        )
        cases.append((ok, "returns = advantages + values"))

    def picture(advantages: np.ndarray, colour: str) -> str:
        ends = np.flatnonzero(starts[:, 0])
        series = [Series("advantage, environment 0", np.arange(steps), advantages[:, 0], colour=colour)]
        series.append(Series("episode starts", ends, advantages[ends, 0], line=False, markers=True, colour="#000000"))
        return line_plot_svg(series, "GAE over the rollout", "step t", "advantage", width=420, height=260)

    return _report("GAE", cases, None if got is None else picture(got, YOURS), picture(expected, REFERENCE))


# --- 06: the spade's success rule -----------------------------------------------------------------
def check_spade_success(student: Callable[..., Any], seed: int = 0) -> bool:
    """Notebook 06: ``student(in_box, success_count)`` -> (B,) bool, where ``in_box`` (B, T) counts
    the spheres in the goal box after each step, against the scenes' ``SuccessTracker`` (met on at
    least half of the steps). Seeded episodes near the boundary (the picture: their counts)."""
    from toolimit.scenes.base import SUCCESS_FRACTION, SuccessTracker

    rng = np.random.default_rng(seed)
    episodes, steps, success_count = 8, 60, 10
    rise = rng.integers(5, 55, size=episodes)
    level = rng.integers(6, 25, size=episodes)
    time = np.arange(steps)
    in_box = np.where(time[None] >= rise[:, None], level[:, None], 0) + rng.integers(-2, 3, size=(episodes, steps))
    in_box = np.clip(in_box, 0, None)
    tracker = SuccessTracker(episodes)
    for t in range(steps):
        tracker.record(in_box[:, t] >= success_count)
    expected = tracker.is_success()
    value, problem = _call(student, in_box.copy(), success_count)
    got = _array(value)
    if problem is None and (got is None or got.shape != (episodes,)):
        problem = f"expected a ({episodes},) bool array, got {value!r:.80}"
    cases = []
    if problem is not None:
        cases.append((False, problem))
        got = None
    else:
        got = got.astype(bool)
        for b in range(episodes):
            met = int(np.sum(in_box[b] >= success_count))
            cases.append(
                (
                    got[b] == expected[b],
                    f"episode {b}: goal met on {met} of {steps} steps "
                    f"(needs {SUCCESS_FRACTION:g} of them): expected {bool(expected[b])}, got {bool(got[b])}",
                )
            )

    def picture(verdicts: np.ndarray, colour: str) -> str:
        series = [
            Series(
                f"episode {b}: {'success' if verdicts[b] else 'failure'}",
                time,
                in_box[b],
                colour=colour if verdicts[b] else "#999999",
            )
            for b in range(4)
        ]
        series.append(Series("success count", time, np.full(steps, success_count), colour="#000000", dashed=True))
        return line_plot_svg(series, "spheres in the box", "step", "spheres", width=420, height=260)

    return _report(
        "spade success rule", cases, None if got is None else picture(got, YOURS), picture(expected, REFERENCE)
    )
