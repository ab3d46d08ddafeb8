"""Selecting the alignment candidate a robot reproduces: the planar arm and the planar spade."""

from __future__ import annotations

import json

import numpy as np
import pytest

from toolimit.align import AlignmentConfig
from toolimit.align.outputs import CANDIDATES_NPZ, write_alignment
from toolimit.align.search import align
from toolimit.cli import main
from toolimit.demos import load_demo
from toolimit.trajopt.selection import load_candidates


@pytest.fixture(scope="module")
def spade_alignment(tmp_path_factory, repo_root):
    """A planar alignment of a shipped spade demo (5 candidates, seed 0)."""
    demo_path = repo_root / "data" / "demos" / "spade_04.npz"
    result = align(load_demo(demo_path), "spade", "planar", AlignmentConfig(candidates=5), seed=0, progress=False)
    out = tmp_path_factory.mktemp("align")
    write_alignment(result, out, str(demo_path))
    return result, out


def test_candidates_file_holds_every_candidate(spade_alignment):
    result, out = spade_alignment
    tool, world, candidates = load_candidates(out / CANDIDATES_NPZ)
    assert (tool, world) == ("spade", "planar")
    assert [c.alignment_reward for c in candidates] == [c.reward for c in result.candidates]
    for loaded, candidate in zip(candidates, result.candidates):
        poses = result.episode_poses(candidate)  # the poses the speed-limited tool reached
        assert np.allclose(loaded.targets.positions, poses.position)
        assert np.allclose(loaded.targets.rotations, poses.rotation, atol=1e-9)
        assert np.allclose(loaded.params["goal_position"], candidate.sample.params["goal_position"])


def test_malformed_candidates_file_is_named(tmp_path):
    path = tmp_path / CANDIDATES_NPZ
    np.savez(path, tip_position=np.zeros((2, 5, 3)))
    with pytest.raises(ValueError, match="candidates.npz: missing keys"):
        load_candidates(path)
    with pytest.raises(FileNotFoundError, match="toolimit align"):
        load_candidates(tmp_path / "absent.npz")


def test_planar_arm_replay_of_the_selected_candidate_earns_reward(spade_alignment, tmp_path, capsys):
    """The robot issue's check: the planar arm tracks an aligned planar spade demo and its joint
    trajectory, replayed in the planar scene, moves sand into the goal box."""
    _, alignment = spade_alignment
    out = tmp_path / "planar3"
    argv = ["trajopt", "--robot", "planar3", "--tool", "spade", "--alignment", str(alignment),
            "--velocity-weight", "1e-4", "--init", "hold", "--quiet", "--out", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    selection = json.loads((out / "selection.json").read_text())
    best = selection["candidates"][selection["best"]]
    assert best["robot_reward"] > 0.0
    assert best["robot_reward"] == max(c["robot_reward"] or 0.0 for c in selection["candidates"])
    record = json.loads((out / "trajectory.json").read_text())
    assert record["limit_violations"] == 0 and record["velocity_violations"] == 0
    printed = capsys.readouterr()
    lines = [line for line in printed.out.splitlines() if line.startswith("candidate ")]
    assert len(lines) == len(selection["candidates"]) and all("rotation error median" in line for line in lines)
    for line, entry in zip(lines, selection["candidates"]):
        if entry["median_rotation_error_rad"] is not None:
            assert f"rotation error median {np.degrees(entry['median_rotation_error_rad']):.0f} deg" in line
            assert ("UPSIDE DOWN" in line) == entry["upside_down"] == (entry["median_rotation_error_rad"] > np.pi / 2)
    assert ("tracked upside down" in printed.err) == record["upside_down"]


def test_selection_keeps_the_time_scale_whose_robot_replay_earns_most(spade_alignment, tmp_path, capsys):
    _, alignment = spade_alignment
    out = tmp_path / "planar3"
    argv = ["trajopt", "--robot", "planar3", "--tool", "spade", "--alignment", str(alignment),
            "--velocity-weight", "1e-4", "--init", "hold", "--starts", "2", "--time-scale", "2,1", "--quiet",
            "--out", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    selection = json.loads((out / "selection.json").read_text())
    for entry in selection["candidates"]:
        by_scale = entry["robot_reward_by_time_scale"]
        assert set(by_scale) == {"1", "2"}
        earned = [reward for reward in by_scale.values() if reward is not None]
        assert entry["robot_reward"] == (max(earned) if earned else None)
        if entry["robot_reward"] is not None and len(set(earned)) == 2:
            assert by_scale[f"{entry['time_scale']:g}"] == entry["robot_reward"]
    best = selection["candidates"][selection["best"]]
    assert json.loads((out / "trajectory.json").read_text())["time_scale"] == best["time_scale"]


def test_selection_is_the_same_with_two_worker_processes(spade_alignment, tmp_path, capsys):
    """Candidates tracked side by side in spawned workers give the selection of one process."""
    _, alignment = spade_alignment
    records = []
    for workers in ("1", "2"):
        out = tmp_path / f"workers{workers}"
        argv = ["trajopt", "--robot", "planar3", "--tool", "spade", "--alignment", str(alignment),
                "--velocity-weight", "1e-4", "--init", "hold", "--starts", "2", "--quiet", "--workers", workers,
                "--out", str(out)]
        assert main(argv) == 0, capsys.readouterr().err
        records.append(json.loads((out / "selection.json").read_text()))
    assert records[0] == records[1]  # same machine, same process type: bit for bit
