"""Real-robot export: retiming within the published limits (checked independently by finite
differences of the written CSV), refusals, files and their content, atomic behaviour."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from toolimit.artifacts import save_npz
from toolimit.deploy import (
    PathOutsideLimits,
    export_trajectory,
    load_trajectory,
    published_limits,
    retime,
)
from toolimit.deploy.export import SUMMARY_JSON, TRAJECTORY_CSV, PathDeviation
from toolimit.robots.limits import Margins

DT = 1.0 / 24.0
PANDA = published_limits("panda")
#: The limits an export keeps by default: 0.01 rad inside the positions, 0.95 of the rest.
NARROWED = PANDA.within(Margins())
#: No margin at all: the published limits themselves.
NO_MARGIN = Margins(position=0.0, velocity=1.0, acceleration=1.0, jerk=1.0)

PANDA_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
#: a comfortable configuration, well inside every Panda joint range (rad)
PANDA_MIDDLE = np.array([0.0, -0.3, 0.0, -1.8, 0.0, 1.6, 0.8])


def bump(amplitude: float, omega: float, times: np.ndarray) -> np.ndarray:
    """amplitude (1 - cos(omega t))^2 / 4: rises from rest (zero velocity and acceleration) to
    ``amplitude`` at half a period and back to rest at a full period (rad, t in s, omega rad/s)."""
    return amplitude * (1.0 - np.cos(omega * times)) ** 2 / 4.0


@pytest.fixture
def write_trajectory(tmp_path: Path) -> Callable[..., Path]:
    """Write DIR/trajectory.npz for q (T+1, 7) sampled every dt; returns DIR."""

    def write(q: np.ndarray, dt: float, name: str = "trajopt") -> Path:
        directory = tmp_path / name
        save_npz(
            directory / "trajectory.npz",
            q=q,
            v=np.diff(q, axis=0) / dt,
            base=np.array([0.2, -0.1, 1.5]),
            joint_names=np.array(PANDA_JOINTS),
            dt=dt,
        )
        return directory

    return write


def slow_smooth(dt: float = 1.0 / 24.0, duration: float = 4.0) -> np.ndarray:
    """(T+1, 7) a gentle motion of every joint around PANDA_MIDDLE, one full period (rest to rest)."""
    times = np.arange(round(duration / dt) + 1) * dt
    omega = 2.0 * np.pi / duration
    return PANDA_MIDDLE + np.outer(bump(1.0, omega, times), [0.4, 0.3, -0.3, 0.4, 0.5, -0.4, 0.6])


def _read_csv(path):
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    return rows[0], np.array(rows[1:], dtype=float)


def _assert_within_limits_by_finite_differences(times: np.ndarray, q: np.ndarray, limits=NARROWED) -> dict[str, float]:
    """Position, and velocity / acceleration / jerk from finite differences of the positions (with
    the robot at rest before the start and after the end), against ``limits`` (by default the
    Panda's published limits within the default margins); returns each quantity's peak |value| / limit."""
    step = np.diff(times)
    np.testing.assert_allclose(step, step[0], rtol=1e-6)
    h = step[0]
    padded = np.concatenate([np.repeat(q[:1], 3, axis=0), q, np.repeat(q[-1:], 3, axis=0)])
    assert np.all(q >= limits.position_lower) and np.all(q <= limits.position_upper)
    peaks = {}
    for order, name in ((1, "velocity"), (2, "acceleration"), (3, "jerk")):
        ratio = np.abs(np.diff(padded, order, axis=0)) / h**order / getattr(limits, name)
        peaks[name] = float(ratio.max())
        assert peaks[name] <= 1.0 + 1e-6, f"{name} reaches {peaks[name]:.4f} x its limit"
    return peaks


def _export(write_trajectory, tmp_path, q, dt=DT, **kwargs):
    out = tmp_path / "export"
    plan = export_trajectory(load_trajectory(write_trajectory(q, dt)), "panda", out, **kwargs)
    header, table = _read_csv(out / TRAJECTORY_CSV)
    assert header == ["time_s", *PANDA_JOINTS]
    summary = json.loads((out / SUMMARY_JSON).read_text())
    return plan, table[:, 0], table[:, 1:], summary


def test_a_slow_smooth_trajectory_keeps_its_timing(write_trajectory, tmp_path):
    q = slow_smooth()
    plan, times, positions, summary = _export(write_trajectory, tmp_path, q)
    peaks = _assert_within_limits_by_finite_differences(times, positions)
    assert peaks["velocity"] < 0.5
    # within the limits at its own timing: its samples are the control points (one piece per step)
    # and nothing is slowed down: the duration is the optimised 4 s plus the two end spans (2 dt)
    # and no braking (its last step's tiny speed stops within one step)
    assert summary["subdivisions"] == 1 and summary["optimised_duration_s"] == pytest.approx(4.0)
    assert summary["braking_s"] == 0.0
    assert summary["duration_s"] == pytest.approx(4.0 + 2 * DT)
    assert summary["margins"] == Margins().as_dict()
    assert len(times) == math.ceil(summary["duration_s"] * 1000 - 1e-9) + 1 and summary["rate_hz"] == 1000.0
    np.testing.assert_allclose(positions[0], q[0], atol=1e-12)
    np.testing.assert_allclose(positions[-1], q[-1], atol=1e-12)
    assert summary["path_deviation_rad"] < 1e-3  # a smooth path is followed closely
    assert summary["joint_names"] == list(PANDA_JOINTS)
    assert summary["limits"]["jerk_rad_s3"] == pytest.approx(
        [0.95 * j for j in (7500, 3750, 5000, 6250, 7500, 1e4, 1e4)]
    )
    assert all(check["passed"] for check in summary["checks"].values())
    assert summary["checks"]["velocity"]["max_ratio"] == pytest.approx(peaks["velocity"], rel=0.01)
    assert summary["base"]["yaw_rad"] == 1.5
    assert plan.path.duration == summary["duration_s"]


def _bang_bang_into_the_limit(dt: float = DT) -> np.ndarray:
    """Joint 3 runs at its velocity limit onto its upper position limit, turns back in one step and
    runs back (the profile trajectory optimisation gives at its limits); joint 5 zigzags at its limit."""
    upper, speed = PANDA.position_upper[2], PANDA.velocity[2]
    steps = 24
    there = upper - speed * dt * np.arange(steps, -1, -1)
    q = np.tile(PANDA_MIDDLE, (2 * steps + 1, 1))
    q[:, 2] = np.concatenate([there, there[-2::-1]])
    q[:, 4] += PANDA.velocity[4] * dt * np.where(np.arange(len(q)) % 2 == 0, 0.0, 1.0)
    return q


def test_a_trajectory_touching_a_position_limit_is_refused_by_default(write_trajectory, tmp_path):
    q = _bang_bang_into_the_limit()
    with pytest.raises(PathOutsideLimits, match=r"panda_joint3 position 2\.8973 rad .* beyond its limit 2\.8873 rad"):
        export_trajectory(load_trajectory(write_trajectory(q, DT)), "panda", tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_trajectory_at_the_velocity_limits_touching_a_position_limit_is_retimed(write_trajectory, tmp_path):
    """Without margins (the published limits themselves) the retiming reaches the binding limit."""
    q = _bang_bang_into_the_limit()
    assert q[:, 2].max() == PANDA.position_upper[2]
    _, times, positions, summary = _export(write_trajectory, tmp_path, q, margins=NO_MARGIN, subdivisions=4)
    peaks = _assert_within_limits_by_finite_differences(times, positions, PANDA)
    assert positions[:, 2].max() <= PANDA.position_upper[2]  # no overshoot past the limit
    assert peaks["acceleration"] > 0.95  # slowed down just enough: the binding limit is reached
    assert summary["duration_s"] > summary["optimised_duration_s"]
    # the exported path passes within the reported deviation of every optimised sample
    gaps = np.abs(positions[None, :, :] - q[:, None, :]).max(axis=2).min(axis=1)
    assert gaps.max() <= summary["path_deviation_rad"] + 1e-3
    assert summary["path_deviation_rad"] < 0.25 * np.abs(np.diff(q, 2, axis=0)).max()


def test_a_path_far_from_its_samples_is_warned(write_trajectory, tmp_path):
    """One piece per step cuts the bang-bang path's corners by 0.037 rad, past the 0.02 rad tolerance."""
    q = _bang_bang_into_the_limit()
    with pytest.warns(PathDeviation, match=r"departs from the trajectory's samples by up to 0\.037 rad"):
        _export(write_trajectory, tmp_path, q, margins=NO_MARGIN, subdivisions=1)


def test_a_rate_giving_a_handful_of_samples_or_none_is_refused(write_trajectory, tmp_path):
    trajectory = load_trajectory(write_trajectory(np.stack([PANDA_MIDDLE, PANDA_MIDDLE + 1e-3]), DT))  # 0.125 s
    for rate, problem in (
        (1e-3, "rate must be between 10 and 10000 Hz"),
        (1e15, "rate must be between"),
        (10.0, "gives fewer than 10 samples"),
    ):
        with pytest.raises(ValueError, match=problem):
            export_trajectory(trajectory, "panda", tmp_path / "out", rate=rate)
    assert not (tmp_path / "out").exists()


def test_more_subdivisions_stay_closer_to_the_samples_and_take_longer(write_trajectory, tmp_path):
    q = _bang_bang_into_the_limit()
    coarse, fine = (retime(q, DT, PANDA, subdivisions=m) for m in (1, 8))
    assert fine.path_deviation < coarse.path_deviation / 4
    assert fine.duration > coarse.duration
    samples = fine.sample(2000.0)
    _assert_within_limits_by_finite_differences(samples.times, samples.position, PANDA)


def test_only_the_fast_part_is_slowed_down():
    gentle = slow_smooth(duration=4.0)
    times = DT * np.arange(13)
    burst = gentle[-1] + np.outer(bump(1.0, 2 * np.pi / times[-1], times), [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.8])
    q = np.concatenate([gentle, burst[1:]])  # 4 s gentle, then joint 7 out and back in 0.5 s (far too fast)
    path = retime(q, DT, PANDA, subdivisions=4)
    samples = path.sample(1000.0)
    _assert_within_limits_by_finite_differences(samples.times, samples.position, PANDA)
    burst_alone = retime(burst, DT, PANDA, subdivisions=4).duration
    assert burst_alone > 2 * 0.5  # the burst needs at least twice its time
    assert path.duration < 4.0 + burst_alone + 0.1  # the gentle 4 s are not slowed down
    uniform = 4.5 * burst_alone / 0.5  # the burst's stretch applied to the whole motion
    assert path.duration < 0.5 * uniform
    gentle_alone = retime(gentle, DT, PANDA, subdivisions=4).derivative(np.array([2.0]), 0)[0]
    np.testing.assert_allclose(samples.position[2000], gentle_alone, atol=1e-6)  # same timing at t = 2 s


def test_a_path_ending_at_speed_brakes_after_its_end_and_keeps_its_timing():
    # joint 1 from rest up to 2 rad/s within its acceleration limit, ending at that speed (a learnt
    # draw ends where its episode ends): braked after the end, not slowed before it
    acceleration, top = 0.9 * PANDA.acceleration[0], 2.0
    speeds = np.minimum(acceleration * DT * np.arange(1, 25), top)
    q = np.tile(PANDA_MIDDLE, (25, 1))
    q[1:, 0] += np.cumsum(speeds) * DT
    path = retime(q, DT, PANDA)
    assert path.subdivisions == 1
    assert path.braking_steps == math.ceil(top / (PANDA.acceleration[0] * DT)) - 1  # the rest stops the last
    assert path.duration == pytest.approx((len(q) - 1 + 2 + path.braking_steps) * DT)
    samples = path.sample(1000.0)
    _assert_within_limits_by_finite_differences(samples.times, samples.position, PANDA)
    at_end = np.searchsorted(samples.times, len(q) * DT)  # sample k's weight peaks at (k + 1) dt
    assert samples.position[at_end, 0] == pytest.approx(q[-1, 0], abs=0.01)  # the motion's own timing
    assert np.abs(np.gradient(samples.position[:at_end, 0], samples.times[:at_end])).max() > 0.95 * top


def test_too_fast_everywhere_is_retimed_and_respects_every_limit(write_trajectory, tmp_path):
    fast = slow_smooth(duration=0.5)  # the 4 s path in 0.5 s
    _, times, positions, summary = _export(write_trajectory, tmp_path, fast)
    _assert_within_limits_by_finite_differences(times, positions)
    assert summary["duration_s"] > 1.5 * summary["optimised_duration_s"]


def test_refuses_a_path_sample_outside_a_position_limit(write_trajectory, tmp_path):
    q = slow_smooth()
    q[:, 3] = -1.5 + bump(1.5, 2 * np.pi / 4.0, DT * np.arange(len(q)))  # joint 4 up to 0 at 2 s > -0.0698
    message = (
        r"panda_joint4 position 0 rad at sample 48 \(t = 2\.0000 s .*\) is beyond its limit -0\.0798 rad "
        r"by 0\.0798 rad .*no retiming can fix .*\(11 of 97 samples are outside\)"
    )
    with pytest.raises(PathOutsideLimits, match=message):
        export_trajectory(load_trajectory(write_trajectory(q, DT)), "panda", tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_refused_export_leaves_existing_files_untouched(write_trajectory, tmp_path):
    out = tmp_path / "out"
    export_trajectory(load_trajectory(write_trajectory(slow_smooth(), DT)), "panda", out)
    before = {path.name: path.read_bytes() for path in out.iterdir()}
    q = slow_smooth()
    q[10, 0] = 3.0  # beyond 2.8973
    with pytest.raises(PathOutsideLimits, match="panda_joint1 position 3 rad at sample 10"):
        export_trajectory(load_trajectory(write_trajectory(q, DT, name="bad")), "panda", out)
    assert {path.name: path.read_bytes() for path in out.iterdir()} == before


def test_unsupported_robot_and_bad_files_are_refused(write_trajectory, tmp_path):
    directory = write_trajectory(slow_smooth(), DT)
    with pytest.raises(ValueError, match="published .* jerk limits .*'ur5'"):
        export_trajectory(load_trajectory(directory), "ur5", tmp_path / "out")
    with pytest.raises(FileNotFoundError, match="trajectory.npz"):
        load_trajectory(tmp_path / "nowhere")
    bad = tmp_path / "bad"
    bad.mkdir()
    q = slow_smooth()
    np.savez(
        bad / "trajectory.npz",
        q=q,
        v=np.diff(q, axis=0) / DT * 1.01,
        base=np.zeros(3),
        joint_names=np.array(PANDA_JOINTS),
        dt=DT,
    )
    with pytest.raises(ValueError, match=r"trajectory.npz: v\[.*differs from"):
        load_trajectory(bad)
    np.savez(
        bad / "trajectory.npz",
        q=q,
        v=np.diff(q, axis=0) / DT,
        base=np.zeros(2),
        joint_names=np.array(PANDA_JOINTS),
        dt=DT,
    )
    with pytest.raises(ValueError, match=r"base must have shape \(3,\)"):
        load_trajectory(bad)
    np.savez(
        bad / "trajectory.npz",
        q=q,
        v=np.diff(q, axis=0) / DT,
        base=np.zeros(3),
        joint_names=np.array([f"j{i}" for i in range(7)]),
        dt=DT,
    )
    with pytest.raises(ValueError, match="do not match panda's joints"):
        export_trajectory(load_trajectory(bad), "panda", tmp_path / "out")
    with pytest.raises(ValueError, match="subdivisions must be a positive integer"):
        retime(q, DT, PANDA, subdivisions=0)
    assert not (tmp_path / "out").exists()


def test_a_failed_write_leaves_no_partial_export(write_trajectory, tmp_path):
    out = tmp_path / "out"
    (out / SUMMARY_JSON).mkdir(parents=True)  # the summary cannot be renamed into place
    with pytest.raises(OSError):
        export_trajectory(load_trajectory(write_trajectory(slow_smooth(), DT)), "panda", out)
    assert [path.name for path in out.iterdir()] == [SUMMARY_JSON]  # no CSV, no temporary file


def test_a_panda_policys_rollout_exports_within_the_published_limits(tmp_path):
    """The paper's last step: a learnt Panda spade policy's deterministic rollout (here cloned on a
    tiny budget from the shipped task), exported for open-loop execution, checked by finite
    differences of the written CSV."""
    from toolimit.cli import main
    from toolimit.learn.evaluate import evaluate, save_rollout_trajectory
    from toolimit.learn.training import load_policy

    learned = tmp_path / "learned"
    tiny = [
        "--timesteps",
        "0",
        "--envs",
        "2",
        "--clone-rollouts",
        "1",
        "--clone-steps",
        "50",
        "--value-steps",
        "10",
        "--quiet",
    ]
    assert main(["learn", "--env", "toolimit/Spade3D-v0", "--out", str(learned), *tiny]) == 0
    model, task = load_policy(learned)
    rollout = evaluate(model, task, episodes=1, deterministic=True, seed=3).joint_positions[0]
    assert rollout.shape == (task.horizon + 1, 7)
    folder = save_rollout_trajectory(rollout, task, tmp_path / "policy_rollout")
    out = tmp_path / "export"
    export_trajectory(load_trajectory(folder), "panda", out, check=task, check_episodes=2)
    header, table = _read_csv(out / TRAJECTORY_CSV)
    assert header == ["time_s", *PANDA_JOINTS]
    peaks = _assert_within_limits_by_finite_differences(table[:, 0], table[:, 1:])
    assert max(peaks.values()) > 0.1  # the rollout moves the arm: the check is not vacuous
    # The same path at its own timing (learnt within the bound: nothing slowed down, one piece per
    # step), passing within 0.01 rad of every rollout sample, replayed open-loop in the task.
    summary = json.loads((out / SUMMARY_JSON).read_text())
    assert summary["subdivisions"] == 1
    braking = summary["braking_s"]  # the rollout's last step may still move: braked after its end
    assert braking <= 10 * task.control_dt
    assert summary["duration_s"] == pytest.approx((task.horizon + 2) * task.control_dt + braking)
    nearest = [np.min(np.max(np.abs(table[:, 1:] - sample), axis=1)) for sample in rollout]
    assert max(nearest) < 0.01
    assert summary["open_loop"]["episodes"] == 2 and len(summary["open_loop"]["goal_reward"]) == 2
