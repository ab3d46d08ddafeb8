"""``toolimit trajopt``: input errors (exit 2, one line, nothing written) and outputs."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from toolimit.cli import main
from toolimit.robots import make_robot
from toolimit.trajopt import TrajectoryResult


def _write_poses(path: Path, steps: int = 12, **overrides) -> Path:
    """Poses of planar3's tool along a small joint swing (reachable), toolimit's tool frame."""
    robot = make_robot("planar3")
    q = robot.q_neutral + 0.2 * np.sin(np.linspace(0, 1.5, steps))[:, None]
    positions, rotations = robot.tool_poses(q, np.array([0.2, 0.0, 0.0]))
    quaternions = np.array([pin.Quaternion(r).coeffs()[[3, 0, 1, 2]] for r in rotations])  # x,y,z,w -> w,x,y,z
    arrays = {"tip_position": positions, "tip_quaternion_wxyz": quaternions, "fps": 24.0} | overrides
    np.savez(path, **arrays)
    return path


def _args(source: list[str], out: Path, *extra: str) -> list[str]:
    return ["trajopt", "--robot", "planar3", "--tool", "spade", *source, "--out", str(out), "--quiet",
            "--starts", "2", *extra]


def assert_user_error(capsys, argv: list[str], fragment: str, out: Path) -> None:
    try:
        code = main(argv)
    except SystemExit as usage_error:  # a value the flag's own parser refuses: argparse's one line
        code = usage_error.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert fragment in err, err
    assert not out.exists() or not any(out.iterdir())


def test_poses_file_gives_a_trajectory(tmp_path, capsys):
    poses = _write_poses(tmp_path / "poses.npz")
    out = tmp_path / "out"
    assert main(_args(["--poses", str(poses)], out, "--rerun", str(tmp_path / "view.rrd"))) == 0
    result = TrajectoryResult.load(out)
    assert result.robot == "planar3" and result.q.shape == (13, 3)
    assert result.limit_violations == 0 and result.velocity_violations == 0
    assert np.median(result.position_error) < 0.02
    assert (tmp_path / "view.rrd").stat().st_size > 0
    printed = capsys.readouterr().out
    assert "planar3: time scale 1" in printed
    assert printed.splitlines()[-1].startswith(f"wrote {out / 'trajectory.npz'} and {out / 'trajectory.json'} (export")


def test_unknown_robot_is_a_one_line_error(capsys, tmp_path):
    poses = _write_poses(tmp_path / "poses.npz")
    argv = _args(["--poses", str(poses)], tmp_path / "out")
    argv[argv.index("planar3")] = "kuka"
    assert_user_error(capsys, argv, "--robot: unknown robot 'kuka'; choose one of planar3, panda", tmp_path / "out")


def test_usage_errors_are_one_line(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["trajopt", "--robot", "panda", "--tool", "spade", "--poses", "p.npz", "--init", "sideways", "--out", "o"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("toolimit trajopt: error: argument --init: invalid choice"), err


def test_an_unwritable_out_is_refused_before_any_work(capsys, tmp_path):
    (tmp_path / "plain").write_text("a file")
    poses = _write_poses(tmp_path / "poses.npz")
    out = tmp_path / "plain" / "out"
    assert_user_error(capsys, _args(["--poses", str(poses)], out), "is a file, not a folder", out)


def test_poses_and_auto_time_scale(tmp_path):
    poses = tmp_path / "poses.npz"
    _write_poses(poses)
    out = tmp_path / "out"
    assert main(_args(["--poses", str(poses)], out, "--time-scale", "auto", "--velocity-weight", "1e-6")) == 0
    document = json.loads((out / "trajectory.json").read_text())
    assert document["time_scale"] == 1.0  # a reachable, slow motion: real time suffices
    assert document["statistics"]["time_scale_search"]["threshold_met"]


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        (["--time-scale", "fast"], "--time-scale"),
        (["--time-scale", "-1"], "--time-scale"),
        (["--time-scale", "1,,2"], "--time-scale"),
        (["--time-scale", "1,nan"], "--time-scale"),
        (["--starts", "0"], "--starts"),
        (["--seed", "-3"], "--seed"),
        (["--velocity-weight", "-1"], "--velocity-weight"),
        (["--rerun", "view.txt"], "--rerun"),
        (["--action-limit", "0"], "--action-limit"),
        (["--action-limit", "3"], "--action-limit: only with --alignment"),
    ],
)
def test_bad_options_are_user_errors(capsys, tmp_path, extra, fragment):
    poses = _write_poses(tmp_path / "poses.npz")
    out = tmp_path / "out"
    assert_user_error(capsys, _args(["--poses", str(poses)], out, *extra), fragment, out)


def test_bad_inputs_are_user_errors(capsys, tmp_path):
    out = tmp_path / "out"
    assert_user_error(capsys, _args(["--poses", str(tmp_path / "none.npz")], out), "none.npz", out)
    assert_user_error(capsys, _args(["--alignment", str(tmp_path)], out), "candidates.npz", out)
    bad = _write_poses(tmp_path / "bad.npz", tip_quaternion_wxyz=np.zeros((12, 3)))
    assert_user_error(capsys, _args(["--poses", str(bad)], out), "tip_quaternion_wxyz", out)
    missing = tmp_path / "missing.npz"
    np.savez(missing, tip_position=np.zeros((3, 3)))
    assert_user_error(capsys, _args(["--poses", str(missing)], out), "missing keys", out)
    argv = _args(["--poses", str(_write_poses(tmp_path / "p.npz"))], out)
    argv[argv.index("spade")] = "rake"
    assert_user_error(capsys, argv, "--tool", out)


def test_real_recording_in_the_original_spade_frame(tmp_path, video_demos_dir):
    out = tmp_path / "out"
    recording = video_demos_dir / "spade_example_aligned.npz"
    argv = ["trajopt", "--robot", "ur5", "--tool", "spade", "--poses", str(recording),
            "--frame", "original-spade", "--out", str(out), "--quiet", "--starts", "1", "--time-scale", "2"]
    assert main(argv) == 0
    result = TrajectoryResult.load(out)
    assert result.q.shape == (93, 6) and result.time_scale == 2.0 and result.dt == pytest.approx(2 / 24)
    assert result.limit_violations == 0 and result.velocity_violations == 0
