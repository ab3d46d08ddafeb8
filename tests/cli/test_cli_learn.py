"""toolimit learn / evaluate / run: tiny budgets, resume, and one-line errors for bad input."""

from __future__ import annotations

import json

import pytest

from toolimit.cli import main

TINY = ["--timesteps", "0", "--envs", "2", "--clone-rollouts", "2", "--clone-steps", "10", "--value-steps", "10", "--quiet"]


def _error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_learn_from_a_registered_id_then_evaluate(tmp_path, capsys):
    out = tmp_path / "learned"
    assert main(["learn", "--env", "toolimit/SpadePlanar-v0", "--out", str(out), *TINY]) == 0
    assert "Next: toolimit evaluate" in capsys.readouterr().out
    assert main(["evaluate", "--policy", str(out), "--episodes", "2"]) == 0
    record = json.loads((out / "evaluation.json").read_text())
    assert record["episodes"] == 2 and {"success_rate", "goal_reward_mean", "stochastic"} <= set(record)


def test_learn_with_adr_then_a_heat_map(tmp_path, capsys):
    out = tmp_path / "learned"
    assert main(["learn", "--env", "toolimit/SpadePlanar-v0", "--adr", "--out", str(out), *TINY]) == 0
    assert "adr" in json.loads((out / "learning.json").read_text())
    svg, rrd = tmp_path / "map.svg", tmp_path / "map.rrd"
    assert main(["evaluate", "--policy", str(out), "--episodes", "2", "--heat-map", str(svg), "--grid", "3",
                 "--rerun", str(rrd)]) == 0
    assert svg.read_text().count('class="cell"') == 3 and rrd.is_file()
    record = json.loads((out / "evaluation.json").read_text())
    assert len(record["heat_map"]["goal_rewards"][0]) == 3 and record["heat_map"]["observes_box"]
    assert record["heat_map"]["episodes"] == 4  # per position by default
    assert main(["evaluate", "--policy", str(out), "--heat-map", str(svg), "--grid", "3", "--heat-map-episodes", "0"]) == 2
    assert "--heat-map-episodes: must be an integer >= 1, got 0" in _error_line(capsys)
    assert main(["evaluate", "--policy", str(out), "--heat-map", str(tmp_path / "map.png")]) == 2
    assert "--heat-map: expected a .svg file name" in _error_line(capsys)


def test_resuming_a_checkpoint_of_an_earlier_adr_rule_is_one_line_exit_2(tmp_path, capsys):
    out = tmp_path / "learned"
    assert main(["learn", "--env", "toolimit/SpadePlanar-v0", "--adr", "--out", str(out), *TINY]) == 0
    state_path = out / "checkpoint.json"
    state = json.loads(state_path.read_text())
    del state["adr"]["rule_version"], state["adr"]["buffers"]  # as the return rule wrote it
    state_path.write_text(json.dumps(state))
    capsys.readouterr()
    more = [*TINY[:1], "100", *TINY[2:]]
    assert main(["learn", "--env", "toolimit/SpadePlanar-v0", "--adr", "--out", str(out), *more]) == 2
    line = _error_line(capsys)
    assert str(state_path) in line and "written by an earlier ADR rule" in line and "new output folder" in line


@pytest.mark.parametrize(("argv", "message"), [
    (["learn", "--env", "toolimit/Shovel3D-v0"], "--env: unknown id 'toolimit/Shovel3D-v0'"),
    (["learn", "--task", "absent.npz"], "absent.npz: no such task file"),
    (["learn", "--alignment", "absent"], "--alignment: needs --trajectory"),
    (["learn", "--env", "toolimit/SpadePlanar-v0", "--robot", "ur5"],
     "no shipped task for the spade in planar with robot ur5"),
    (["learn", "--env", "toolimit/SpadePlanar-v0", "--envs", "0"], "--envs: must be an integer >= 1"),
    (["learn", "--env", "toolimit/SpadePlanar-v0", "--action-std", "0"], "--action-std: must be a finite number > 0"),
    (["learn", "--env", "toolimit/SpadePlanar-v0", "--target-kl", "0"], "--target-kl: must be a finite number > 0"),
    (["evaluate", "--policy", "absent"], "--policy: no such folder"),
    (["learn", "--env", "toolimit/HammerPlanar-v0", "--adr"], "the hammer scene has none (only the spades)"),
    (["learn", "--env", "toolimit/SpadePlanar-v0", "--adr-every", "0"], "--adr-every: must be an integer >= 1"),
    (["run", "--tool", "spade", "--robot", "panda", "--demo", "absent.npz", "--time-scale", "slow"],
     "--time-scale: expected positive numbers"),
])
def test_bad_input_gets_one_line(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    try:
        code = main([*argv, *([] if argv[0] == "evaluate" else ["--out", "out"])])
    except SystemExit as usage_error:  # a value the flag's own parser refuses: argparse's one line
        code = usage_error.code
    assert code == 2
    assert message in _error_line(capsys)
    assert not (tmp_path / "out").exists()


def test_learn_from_a_missing_stage_output(tmp_path, capsys):
    (tmp_path / "alignment").mkdir()
    assert main(["learn", "--alignment", str(tmp_path / "alignment"), "--trajectory", str(tmp_path / "trajectory"),
                 "--out", str(tmp_path / "out"), *TINY]) == 2
    assert "trajectory.npz: no such file" in _error_line(capsys)
