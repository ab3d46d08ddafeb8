"""``toolimit replay``: input errors (exit 2, one line, nothing written) and the reported figures."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from toolimit.cli import main
from toolimit.scenes.spatial.scoop import scripted_scoop

PARAMS = {"sand_position": [0.0, 0.0, 0.0], "sand_yaw": 0.0, "goal_position": [0.0, 0.9, 0.0]}
SHARED = Path(os.environ.get("TOOLIMIT_SHARED", Path(__file__).resolve().parents[3] / "shared"))
REAL_SPADE = SHARED / "data" / "video_demos" / "spade_video1_aligned.npz"


def write_poses(path: Path, frames: int = 109, **overrides) -> Path:
    """The scripted scoop for PARAMS (toolimit's tool frame) as a poses file."""
    motion = scripted_scoop({k: np.asarray(v, dtype=float) for k, v in PARAMS.items()})
    quaternions = np.array([pin.Quaternion(r).coeffs()[[3, 0, 1, 2]] for r in motion.rotation[:frames]])
    np.savez(path, **({"tip_position": motion.position[:frames], "tip_quaternion_wxyz": quaternions, "fps": 24.0}
                      | overrides))
    return path


def write_params(path: Path, params: object = PARAMS) -> Path:
    path.write_text(json.dumps(params))
    return path


def assert_user_error(capsys, argv: list[str], fragment: str, out: Path) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert fragment in err, err
    assert not out.exists()


def test_replay_reports_the_goal_reward_of_every_replay(tmp_path: Path, capsys) -> None:
    poses, params, out = write_poses(tmp_path / "scoop.npz"), write_params(tmp_path / "p.json"), tmp_path / "r.json"
    argv = ["replay", "--tool", "spade", "--world", "3d", "--poses", str(poses), "--params", str(params),
            "--replays", "2", "--seed", "0", "--json", str(out)]
    assert main(argv) == 0
    assert "goal reward mean" in capsys.readouterr().out
    record = json.loads(out.read_text())
    # the scripted scoop within the tool speed limit (the tool-alone replay's): 9 and 11 spheres
    assert len(record["goal_reward"]) == 2 and min(record["goal_reward"]) >= 5, record["goal_reward"]
    assert record["goal_reward_mean"] == pytest.approx(np.mean(record["goal_reward"]))
    assert 0.0 <= record["success_rate"] <= 1.0
    assert record["params"] == PARAMS and record["frames"] == 109
    # Same seed, same figures.
    again = tmp_path / "again.json"
    assert main(argv[:-1] + [str(again)]) == 0
    assert json.loads(again.read_text())["goal_reward"] == record["goal_reward"]


def test_replay_reads_the_authors_parameters_from_their_aligned_file(tmp_path: Path, capsys) -> None:
    if not REAL_SPADE.is_file():
        pytest.skip(f"the authors' spade recording is not available ({REAL_SPADE} missing)")
    out = tmp_path / "real.json"
    argv = ["replay", "--tool", "spade", "--world", "3d", "--poses", str(REAL_SPADE), "--frame", "original-spade",
            "--params-from-poses", "--replays", "2", "--json", str(out)]
    assert main(argv) == 0
    record = json.loads(out.read_text())
    data = np.load(REAL_SPADE)
    np.testing.assert_allclose(record["params"]["sand_position"], data["sand_buffer_position"])
    assert record["params"]["sand_yaw"] == pytest.approx(float(data["sand_buffer_yaw"]))
    assert record["goal_reward_mean"] > 0


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        ({"world": "4d"}, "--world"),
        ({"tool": "rake"}, "--tool"),
        ({"replays": "0"}, "--replays"),
        ({"poses": "missing.npz"}, "no such file"),
        ({"params_text": "{not json"}, "not valid JSON"),
        ({"params_text": json.dumps([1, 2])}, "JSON object"),
        ({"params_text": json.dumps(PARAMS | {"sand_heigth": 1.0})}, "unknown parameters ['sand_heigth']"),
        ({"params_text": json.dumps(PARAMS | {"goal_position": [0.1, 0.1, 0.0]})}, "overlap"),
        ({"params_text": json.dumps({"sand_yaw": 0.0})}, "missing parameter"),
        ({"fps": 30.0}, "30 fps"),
        ({"from_poses": True}, "lacks"),
        ({"html": "view.png"}, "--html"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_nothing_written(tmp_path: Path, capsys, change: dict, fragment: str) -> None:
    poses = write_poses(tmp_path / "scoop.npz", frames=5, **({"fps": change["fps"]} if "fps" in change else {}))
    params = tmp_path / "p.json"
    params.write_text(change.get("params_text", json.dumps(PARAMS)))
    out = tmp_path / "out.json"
    argv = ["replay", "--tool", change.get("tool", "spade"), "--world", change.get("world", "3d"),
            "--poses", str(tmp_path / change["poses"]) if "poses" in change else str(poses),
            "--replays", change.get("replays", "2"), "--json", str(out)]
    argv += ["--params-from-poses"] if change.get("from_poses") else ["--params", str(params)]
    if "html" in change:
        argv += ["--html", str(tmp_path / change["html"])]
    assert_user_error(capsys, argv, fragment, out)
