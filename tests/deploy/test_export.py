"""Real-robot export: limit checks (each quantity), files and their content, atomic behaviour."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from conftest import PANDA_JOINTS, PANDA_MIDDLE, bump, bump_peaks, slow_smooth

from toolimit.deploy import (
    LimitViolation,
    export_trajectory,
    fit_joint_spline,
    load_trajectory,
    minimal_time_scale,
    published_limits,
)
from toolimit.deploy.export import CONTROL_CSV, RESAMPLED_CSV, SUMMARY_JSON

DT = 1.0 / 24.0


def _read_csv(path):
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    return rows[0], np.array(rows[1:], dtype=float)


def test_accepts_a_slow_smooth_trajectory_and_writes_csv_and_json(write_trajectory, tmp_path):
    q = slow_smooth()
    trajectory = load_trajectory(write_trajectory(q, DT))
    out = tmp_path / "export"
    plan = export_trajectory(trajectory, "panda", out, rate=1000.0)
    assert plan.passed

    header, control = _read_csv(out / CONTROL_CSV)
    assert header == ["time_s", *PANDA_JOINTS]
    np.testing.assert_allclose(control[:, 0], DT * np.arange(len(q)), atol=1e-9)
    np.testing.assert_allclose(control[:, 1:], q, atol=1e-9)

    header, resampled = _read_csv(out / RESAMPLED_CSV)
    assert header == ["time_s", *PANDA_JOINTS]
    assert len(resampled) == 4001  # 4 s at 1 kHz, both ends included
    np.testing.assert_allclose(np.diff(resampled[:, 0]), 1e-3, atol=1e-9)
    np.testing.assert_allclose(resampled[0, 1:], q[0], atol=1e-9)
    np.testing.assert_allclose(resampled[-1, 1:], q[-1], atol=1e-9)
    # 1 kHz samples that coincide with control samples (every 125 ms = 3 control steps) equal them
    np.testing.assert_allclose(resampled[::125, 1:], q[::3], atol=1e-9)

    summary = json.loads((out / SUMMARY_JSON).read_text())
    assert summary["joint_names"] == list(PANDA_JOINTS)
    assert summary["resampled_rate_hz"] == 1000.0
    assert summary["control_rate_hz"] == pytest.approx(24.0)
    assert summary["units"]["jerk"] == "rad/s^3"
    assert summary["limits"]["acceleration_rad_s2"] == [15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0]
    assert summary["limits"]["jerk_rad_s3"] == [7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0]
    assert all(check["passed"] for check in summary["checks"].values())
    # joint 7 moves fastest (0.6 rad bump in 4 s)
    expected_ratio = bump_peaks(0.6, np.pi / 2)["velocity"] / 2.61
    assert summary["checks"]["velocity"]["max_ratio"] == pytest.approx(expected_ratio, rel=0.01)
    assert summary["checks"]["velocity"]["worst_joint"] == "panda_joint7"
    assert summary["base"]["yaw_rad"] == 1.5


def test_resampled_trajectory_passes_through_the_control_samples_and_starts_and_ends_at_rest():
    q = slow_smooth()
    spline = fit_joint_spline(q, DT)
    times = DT * np.arange(len(q))
    np.testing.assert_allclose(spline.derivative(times, 0), q, atol=1e-12)
    for order in (1, 2):
        np.testing.assert_allclose(spline.derivative(times[[0, -1]], order), 0.0, atol=1e-9)
    np.testing.assert_array_equal(spline.derivative(np.array([times[-1] + 1.0]), 0)[0], q[-1])


def test_refuses_a_position_violation(write_trajectory, tmp_path):
    q = slow_smooth()
    q[:, 3] = -1.5 + bump(1.5, 2 * np.pi / 4.0, DT * np.arange(len(q)))  # joint 4 up to 0 at 2 s > -0.0698
    message = r"panda_joint4 position .* at t = 2\.0000 s is outside its limit -0\.0698"
    with pytest.raises(LimitViolation, match=message) as error:
        export_trajectory(load_trajectory(write_trajectory(q, DT)), "panda", tmp_path / "out")
    assert error.value.minimal_time_scale is None
    assert "slowing down cannot fix" in str(error.value)
    assert not (tmp_path / "out").exists()


def _only_failing(checks, quantity):
    by_quantity = {check.quantity: check for check in checks}
    assert [name for name, check in by_quantity.items() if not check.passed] == [quantity]
    return by_quantity[quantity]


def test_refuses_a_velocity_violation_and_offers_a_time_scale(write_trajectory, tmp_path):
    times = DT * np.arange(111)  # one period of 110 steps
    omega = 2 * np.pi / times[-1]
    q = np.tile(PANDA_MIDDLE, (len(times), 1))
    q[:, 0] = -1.4 + bump(2.8, omega, times)  # joint 1: 2.49 rad/s > 2.175 at a third of the period
    trajectory = load_trajectory(write_trajectory(q, DT))
    message = r"panda_joint1 velocity 2\.4\d* rad/s at t = 1\.5\d* s exceeds the limit \+-2\.175"
    with pytest.raises(LimitViolation, match=message) as error:
        export_trajectory(trajectory, "panda", tmp_path / "out")
    peak = bump_peaks(2.8, omega)["velocity"]
    assert _only_failing(error.value.checks, "velocity").ratio == pytest.approx(peak / 2.175, rel=1e-3)
    scale = error.value.minimal_time_scale
    assert scale == pytest.approx(peak / 2.175, abs=2e-3)
    assert not (tmp_path / "out").exists()
    # the offered time scale passes, and slightly below it does not
    assert export_trajectory(trajectory, "panda", tmp_path / "out", time_scale=scale).passed
    with pytest.raises(LimitViolation):
        export_trajectory(trajectory, "panda", tmp_path / "out2", time_scale=scale - 2e-3)


def test_refuses_an_acceleration_violation(write_trajectory, tmp_path):
    times = DT * np.arange(97)  # 8 periods of 12 steps (0.5 s)
    q = np.tile(PANDA_MIDDLE, (len(times), 1))
    q[:, 1] += bump(0.1, 4 * np.pi, times)  # joint 2: 15.8 rad/s^2 > 7.5 (0.8 rad/s, 0.4 of the jerk limit)
    message = r"panda_joint2 acceleration -15\.\d* rad/s\^2 at t = .* exceeds the limit \+-7\.5 "
    with pytest.raises(LimitViolation, match=message) as error:
        export_trajectory(load_trajectory(write_trajectory(q, DT)), "panda", tmp_path / "out")
    peak = bump_peaks(0.1, 4 * np.pi)["acceleration"]
    assert _only_failing(error.value.checks, "acceleration").ratio == pytest.approx(peak / 7.5, rel=0.02)


def test_refuses_a_jerk_violation(write_trajectory, tmp_path):
    dt = 5e-4  # a finely sampled vibration: 20 periods of 12 samples (6 ms), 5 micro-rad
    times = dt * np.arange(241)
    omega = 2 * np.pi / (12 * dt)
    q = np.tile(PANDA_MIDDLE, (len(times), 1))
    q[:, 1] += bump(5e-6, omega, times)  # joint 2: 5.5 rad/s^2 < 7.5 but 7850 rad/s^3 > 3750
    message = r"panda_joint2 jerk .* rad/s\^3 at t = .* exceeds the limit \+-3750 "
    with pytest.raises(LimitViolation, match=message) as error:
        export_trajectory(load_trajectory(write_trajectory(q, dt)), "panda", tmp_path / "out", rate=20000.0)
    peak = bump_peaks(5e-6, omega)["jerk"]
    assert _only_failing(error.value.checks, "jerk").ratio == pytest.approx(peak / 3750, rel=0.05)


def test_a_refused_export_leaves_existing_files_untouched(write_trajectory, tmp_path):
    out = tmp_path / "out"
    export_trajectory(load_trajectory(write_trajectory(slow_smooth(), DT)), "panda", out)
    before = {path.name: path.read_bytes() for path in out.iterdir()}
    fast = slow_smooth(duration=0.5)  # the same path in 0.5 s: far too fast
    with pytest.raises(LimitViolation):
        export_trajectory(load_trajectory(write_trajectory(fast, DT, name="fast")), "panda", out)
    assert {path.name: path.read_bytes() for path in out.iterdir()} == before


def test_minimal_time_scale_is_one_for_a_passing_trajectory(write_trajectory):
    trajectory = load_trajectory(write_trajectory(slow_smooth(), DT))
    assert minimal_time_scale(trajectory, published_limits("panda")) == 1.0


def test_unsupported_robot_and_bad_files_are_refused(write_trajectory, tmp_path):
    directory = write_trajectory(slow_smooth(), DT)
    with pytest.raises(ValueError, match="published .* jerk limits .*'ur5'"):
        export_trajectory(load_trajectory(directory), "ur5", tmp_path / "out")
    with pytest.raises(FileNotFoundError, match="trajectory.npz"):
        load_trajectory(tmp_path / "nowhere")
    bad = tmp_path / "bad"
    bad.mkdir()
    q = slow_smooth()
    np.savez(bad / "trajectory.npz", q=q, v=np.diff(q, axis=0) / DT * 1.01, base=np.zeros(3),
             joint_names=np.array(PANDA_JOINTS), dt=DT)
    with pytest.raises(ValueError, match=r"trajectory.npz: v\[.*differs from"):
        load_trajectory(bad)
    np.savez(bad / "trajectory.npz", q=q, v=np.diff(q, axis=0) / DT, base=np.zeros(2),
             joint_names=np.array(PANDA_JOINTS), dt=DT)
    with pytest.raises(ValueError, match=r"base must have shape \(3,\)"):
        load_trajectory(bad)
    np.savez(bad / "trajectory.npz", q=q, v=np.diff(q, axis=0) / DT, base=np.zeros(3),
             joint_names=np.array([f"j{i}" for i in range(7)]), dt=DT)
    with pytest.raises(ValueError, match="do not match panda's joints"):
        export_trajectory(load_trajectory(bad), "panda", tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_overshoot_between_samples_at_a_limit_is_explained(write_trajectory, tmp_path):
    """Samples that stop exactly at a limit make the interpolant overshoot: refused, and the message says why."""
    q = slow_smooth(duration=2.0)
    upper = published_limits("panda").position_upper[0]
    q[:, 0] = np.minimum(np.linspace(0.0, 2 * upper, len(q)), upper)  # joint 1 runs into its limit and stays
    with pytest.raises(LimitViolation, match="panda_joint1 position .*interpolant overshoots between samples"):
        export_trajectory(load_trajectory(write_trajectory(q, DT)), "panda", tmp_path / "out")


def test_a_failed_write_leaves_no_partial_export(write_trajectory, tmp_path):
    out = tmp_path / "out"
    (out / SUMMARY_JSON).mkdir(parents=True)  # the summary cannot be renamed into place
    with pytest.raises(OSError):
        export_trajectory(load_trajectory(write_trajectory(slow_smooth(), DT)), "panda", out)
    assert [path.name for path in out.iterdir()] == [SUMMARY_JSON]  # no CSV, no temporary file
