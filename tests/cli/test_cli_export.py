"""`toolimit export`: success, one-line refusals with exit code 2, nothing written on error."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from toolimit.artifacts import save_npz
from toolimit.cli import main

JOINTS = np.array([f"panda_joint{i}" for i in range(1, 8)])
DT = 1.0 / 24.0


def _trajectory_dir(tmp_path, duration: float):
    """A rest-to-rest motion of every joint around a middle pose, over ``duration`` s."""
    times = np.arange(round(duration / DT) + 1) * DT
    shape = (1.0 - np.cos(2 * np.pi * times / duration)) ** 2 / 4.0
    q = np.array([0.0, -0.3, 0.0, -1.8, 0.0, 1.6, 0.8]) + np.outer(shape, [0.4, 0.3, -0.3, 0.4, 0.5, -0.4, 0.6])
    directory = tmp_path / f"trajopt_{duration:g}s"
    save_npz(directory / "trajectory.npz", q=q, v=np.diff(q, axis=0) / DT, base=np.array([0.1, 0.2, 0.3]),
             joint_names=JOINTS, dt=DT)
    return directory


def test_export_writes_csv_and_json(tmp_path, capsys):
    out = tmp_path / "robot"
    code = main(["export", "--trajectory", str(_trajectory_dir(tmp_path, 4.0)), "--robot", "panda", "--out", str(out),
                 "--rate", "500"])
    assert code == 0
    assert sorted(path.name for path in out.iterdir()) == ["joint_trajectory.csv", "joint_trajectory.json"]
    summary = json.loads((out / "joint_trajectory.json").read_text())
    # within the limits at its own timing: 4 s + two end spans of dt, up to the next 2 ms
    assert summary["rate_hz"] == 500.0 and summary["n_samples"] == 2043 and summary["open_loop"] is None
    printed = capsys.readouterr().out
    assert re.search(r"retimed within panda's limits \(0\.01 rad .*\): 4\.083 s against 4\.000 s optimised", printed)
    assert printed.splitlines()[-1].startswith(f"wrote {out / 'joint_trajectory.csv'} (2043 samples at 500 Hz)")


def test_check_replays_the_export_open_loop_in_the_task(tmp_path, capsys):
    """--check TASK: the shipped Panda spade task's reference motion, exported and replayed open-loop."""
    from toolimit.learn import shipped_task
    from toolimit.robots import make_robot
    from toolimit.robots.motion_bound import MotionBound

    task = shipped_task("spade", "3d")
    task_file = task.save(tmp_path / "task.npz")
    bound = MotionBound.of(make_robot("panda"))
    q = np.clip(task.reference_q, bound.lower, bound.upper)  # the shipped reference touches joint 2's limit
    directory = tmp_path / "reference"
    save_npz(directory / "trajectory.npz", q=q, v=np.diff(q, axis=0) / task.control_dt, base=task.base,
             joint_names=np.array(task.joint_names), dt=task.control_dt)
    out = tmp_path / "robot"
    code = main(["export", "--trajectory", str(directory), "--robot", "panda", "--out", str(out),
                 "--check", str(task_file), "--check-episodes", "2"])
    assert code == 0
    summary = json.loads((out / "joint_trajectory.json").read_text())
    assert summary["open_loop"]["episodes"] == 2
    line = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("open-loop replay"))
    assert re.fullmatch(r"open-loop replay in .*task\.npz: success [01]\.\d\d over 2 episodes, goal reward \d+\.\d\d", line)


def test_a_too_fast_trajectory_is_slowed_down(tmp_path, capsys):
    code = main(["export", "--trajectory", str(_trajectory_dir(tmp_path, 0.5)), "--robot", "panda",
                 "--out", str(tmp_path / "robot")])
    assert code == 0
    duration, optimised = re.search(r"(\d+\.\d+) s against (\d+\.\d+) s optimised", capsys.readouterr().out).groups()
    assert float(optimised) == 0.5 and float(duration) > 1.0


def _outside_dir(tmp_path):
    directory = _trajectory_dir(tmp_path, 4.0)
    with np.load(directory / "trajectory.npz") as arrays:
        q = arrays["q"].copy()
    q[30:40, 5] = 3.8  # joint 6 beyond its 3.7525 rad limit
    save_npz(directory / "trajectory.npz", q=q, v=np.diff(q, axis=0) / DT, base=np.zeros(3), joint_names=JOINTS, dt=DT)
    return directory


@pytest.mark.parametrize(
    ("make", "robot", "message"),
    [
        (_outside_dir, "panda", r"panda_joint6 position 3\.8 rad at sample 30 .*no retiming can fix"),
        (lambda tmp_path: _trajectory_dir(tmp_path, 4.0), "ur5", r"only robots with published .* 'ur5'"),
    ],
)
def test_refusals_are_one_line_exit_2_and_write_nothing(tmp_path, capsys, make, robot, message):
    out = tmp_path / "robot"
    trajectory = str(make(tmp_path))
    code = main(["export", "--trajectory", trajectory, "--robot", robot, "--out", str(out)])
    assert code == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and error.startswith("toolimit export: error: ")
    assert re.search(message, error), error
    assert not out.exists()


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--rate", "1e15"], r"--rate: must be between 10 and 10000 Hz, got 1e\+15"),
        (["--rate", "1e-3"], r"--rate: must be between 10 and 10000 Hz"),
        (["--velocity-scale", "1.5"], r"--velocity-scale: must be a fraction of the limit in \(0, 1\], got 1\.5"),
        (["--position-margin", "-0.1"], r"--position-margin: must be between 0 and 0\.5 rad"),
        (["--subdivisions", "100000"], r"--subdivisions: must be at most 64"),
    ],
)
def test_bad_settings_are_one_line_exit_2_and_write_nothing(tmp_path, capsys, flags, message):
    out = tmp_path / "robot"
    code = main(["export", "--trajectory", str(_trajectory_dir(tmp_path, 4.0)), "--robot", "panda", "--out", str(out),
                 *flags])
    assert code == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and error.startswith("toolimit export: error: ")
    assert re.search(message, error), error
    assert not out.exists()


def test_missing_trajectory_is_a_one_line_error(tmp_path, capsys):
    code = main(["export", "--trajectory", str(tmp_path / "nothing"), "--robot", "panda", "--out", str(tmp_path / "o")])
    assert code == 2
    assert "trajectory.npz: no such file" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_exports_what_trajopt_saves(tmp_path):
    """The trajectory.npz written by toolimit.trajopt's TrajectoryResult.save is read by the export."""
    from toolimit.trajopt import TrajectoryResult

    source = _trajectory_dir(tmp_path, 4.0)
    with np.load(source / "trajectory.npz") as arrays:
        q, v, base = arrays["q"], arrays["v"], arrays["base"]
    horizon = len(v)
    result = TrajectoryResult(
        robot="panda", tool="spade", joint_names=tuple(JOINTS), q=q, v=v, base=base, dt=DT, time_scale=1.0,
        position_error=np.zeros(horizon), rotation_error=np.zeros(horizon), limit_margin=np.ones_like(q),
        velocity_ratio=np.zeros_like(v),
    )
    saved = result.save(tmp_path / "from_trajopt")
    assert main(["export", "--trajectory", str(saved), "--robot", "panda", "--out", str(tmp_path / "robot")]) == 0
    summary = json.loads((tmp_path / "robot" / "joint_trajectory.json").read_text())
    assert summary["base"]["yaw_rad"] == pytest.approx(0.3)
