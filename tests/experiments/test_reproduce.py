"""``toolimit reproduce --preset quick``: every method's cell measured, saved, reported, and resumed."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from toolimit.cli import main as toolimit
from toolimit.errors import BaseInsideFootprint
from toolimit.experiments.cells import METHODS, CellResult
from toolimit.experiments.report import markdown_table
from toolimit.experiments.summary import summarise_cells
from toolimit.learn.kinesthetic import SELECTION_JSON
from toolimit.learn.task import TASK_NPZ, LearningTask
from toolimit.pipeline.settings import PipelineSettings

REPO = Path(__file__).resolve().parents[2]
EXPERIMENT = "spade-planar-planar3-spade_03"


@pytest.fixture(scope="module")
def quick_results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("reproduce")
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(REPO)  # the preset names the shipped demonstrations relative to the checkout
        assert toolimit(["reproduce", "--preset", "quick", "--out", str(out), "--quiet"]) == 0
    return out


def test_every_method_has_a_cell_with_the_figures_fields(quick_results: Path) -> None:
    cells = json.loads((quick_results / "results.json").read_text())["cells"]
    assert sorted(cell["method"] for cell in cells) == sorted(METHODS)
    for cell in cells:
        assert {"tool", "demo", "robot", "method", "goal_reward", "success_rate"} <= cell.keys()
        assert (cell["tool"], cell["robot"], cell["demo"]) == ("spade", "planar3", "spade_03")
        assert 0.0 <= cell["success_rate"] <= 1.0 and len(cell["goal_rewards"]) == 4
    by_method = {cell["method"]: cell for cell in cells}
    # The aligned motion and the robot's trajectory deliver sand (the shortlist keeps the candidate the
    # robot tracks best, whose tool-alone replay need not reach success); PPO from scratch on 2,000
    # steps does not.
    assert by_method["tool_only"]["goal_reward"] > 0 and by_method["trajopt"]["goal_reward"] >= 10
    assert by_method["sparse_ppo"]["goal_reward"] == 0.0
    assert by_method["final"]["env_steps"] > by_method["sparse_ppo"]["env_steps"] > 0  # cloning rollouts on top
    assert by_method["lfd"]["env_steps"] >= 2_000  # the method's PPO budget (its episodes have their own horizon)
    # learnt policies record their limit use; the planar arm publishes no acceleration limit and
    # no export: its final cell has no open-loop column
    assert by_method["final"]["limits"]["max_acceleration_ratio"] is None
    assert 0.0 <= by_method["final"]["limits"]["share_of_steps_past_limits"] <= 1.0
    assert by_method["final"]["exported"] is None and by_method["tool_only"]["limits"] is None


def test_lfd_learns_from_a_scripted_scoop_the_robot_delivers_in_the_methods_scene(quick_results: Path) -> None:
    folder = quick_results / "seed_0" / EXPERIMENT / "lfd"
    method, lfd = (LearningTask.load(folder / name / TASK_NPZ) for name in ("../method/learning", "."))
    for name, value in method.params.items():
        np.testing.assert_array_equal(lfd.params[name], value)
    demonstration = json.loads((folder / SELECTION_JSON).read_text())["candidates"][0]
    assert demonstration["alignment_reward"] >= 10 and demonstration["robot_reward"] >= 10  # tool alone, robot
    configs = [
        json.loads((folder / "learning.json").read_text())["config"]
        for folder in (
            quick_results / "seed_0" / EXPERIMENT / "lfd" / "learning",
            quick_results / "seed_0" / EXPERIMENT / "method" / "learning",
        )
    ]
    assert configs[0] == configs[1]  # exactly the method's learning flags


def test_the_table_and_the_figure_are_written(quick_results: Path) -> None:
    table = (quick_results / "results.md").read_text()
    assert "| spade | planar | planar3 | spade_03 |" in table
    svg = (quick_results / "results_spade.svg").read_text()
    assert svg.startswith("<svg") and "success (10)" in svg


def test_a_second_run_skips_saved_cells_and_a_removed_cell_comes_back_the_same(
    quick_results: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    removed = quick_results / "seed_0" / "cells" / f"{EXPERIMENT}-trajopt.json"
    before = CellResult.load(removed)
    removed.unlink()
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(REPO)
        assert toolimit(["reproduce", "--preset", "quick", "--out", str(quick_results), "--quiet"]) == 0
    output = capsys.readouterr().out
    assert "[learning] done earlier" in output and "sparse_ppo:" not in output  # only the missing cell ran
    assert CellResult.load(removed) == before  # same seed, same rollouts


def test_markdown_marks_unmeasured_methods() -> None:
    cell = CellResult("hammer", "3d", "panda", "hammer_00", "final", 1.0, 1.0, [1.0], 10, 1.0)
    row = "| hammer | 3d | panda | hammer_00 | - | - | 1.0 [1.0, 1.0] (1.00 [1.00, 1.00]) | - | - | - | - | - |"
    assert markdown_table(summarise_cells({0: [cell]}), [0]).splitlines()[-1] == row


def test_markdown_shows_the_final_policys_limits_and_its_export() -> None:
    limits = {
        "share_of_steps_past_limits": 0.25,
        "max_velocity_ratio": 0.95,
        "max_acceleration_ratio": 3.5,
        "share_of_steps_past_limits_per_episode": [0.25, 0.25],
    }
    exported = {"goal_reward_mean": 12.5, "success_rate": 0.5, "episodes": 2, "goal_reward": [12.5, 12.5]}
    cell = CellResult("spade", "3d", "panda", "spade_00", "final", 15.0, 1.0, [15.0, 15.0], 10, 1.0, limits, exported)
    row = (
        "| spade | 3d | panda | spade_00 | - | - | 15.0 [15.0, 15.0] (1.00 [1.00, 1.00]) | - | - | - | "
        "0.25 [0.25, 0.25] (0.95, 3.50) | 12.5 [12.5, 12.5] (0.50 [0.00, 1.00]) |"
    )
    assert markdown_table(summarise_cells({0: [cell]}), [0]).splitlines()[-1] == row


def test_a_robot_that_cannot_track_the_scripted_motion_leaves_the_lfd_cell_missing(
    quick_results: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "reproduce"
    shutil.copytree(quick_results, out)
    (out / "seed_0" / "cells" / f"{EXPERIMENT}-lfd.json").unlink()
    shutil.rmtree(out / "seed_0" / EXPERIMENT / "lfd")

    def refuse(*args, **kwargs):
        raise BaseInsideFootprint("every one of the 4 solutions puts the robot base inside a scene element")

    monkeypatch.setattr("toolimit.experiments.methods.kinesthetic_task", refuse)
    monkeypatch.chdir(REPO)
    assert toolimit(["reproduce", "--preset", "quick", "--out", str(out), "--quiet"]) == 1
    said = [line for line in capsys.readouterr().out.splitlines() if "lfd:" in line]
    assert said == [
        f"[{EXPERIMENT}] lfd: no kinesthetic demonstration, no cell: every one of the 4 solutions puts the robot "
        "base inside a scene element"
    ]
    cells = json.loads((out / "results.json").read_text())["cells"]
    assert sorted(cell["method"] for cell in cells) == sorted(set(METHODS) - {"lfd"})


def test_a_demonstration_of_an_unknown_tool_is_a_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    demo = tmp_path / "shovel_00.npz"
    demo.write_bytes(b"")
    assert toolimit(["reproduce", "--demo", str(demo), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and "must start with one of spade, hammer, scythe" in error
    assert not (tmp_path / "out").exists()


def test_methods_measures_only_the_named_cells_and_a_later_run_adds_the_others(
    quick_results: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "reproduce"
    shutil.copytree(quick_results, out)
    for method in ("trajopt", "dense_ppo"):
        (out / "seed_0" / "cells" / f"{EXPERIMENT}-{method}.json").unlink()
    monkeypatch.chdir(REPO)
    assert toolimit(["reproduce", "--preset", "quick", "--methods", "dense_ppo", "--out", str(out), "--quiet"]) == 0
    assert not (out / "seed_0" / "cells" / f"{EXPERIMENT}-trajopt.json").exists()
    assert (out / "seed_0" / "cells" / f"{EXPERIMENT}-dense_ppo.json").is_file()
    assert toolimit(["reproduce", "--preset", "quick", "--out", str(out), "--quiet"]) == 0
    assert CellResult.load(out / "seed_0" / "cells" / f"{EXPERIMENT}-trajopt.json") == CellResult.load(
        quick_results / "seed_0" / "cells" / f"{EXPERIMENT}-trajopt.json"
    )


def test_an_unknown_method_is_a_one_line_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        toolimit(["reproduce", "--methods", "final,ppo", "--out", str(tmp_path / "out")])
    assert exit_info.value.code == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and "unknown method(s) ppo" in error
    assert not (tmp_path / "out").exists()


def test_an_interrupted_step_stops_the_whole_reproduction(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import signal

    from toolimit.experiments import reproduce
    from toolimit.interrupts import Interrupted

    steps: list[object] = []

    def interrupted_run(demo: object, *args: object, **kwargs: object) -> None:
        steps.append(demo)
        raise Interrupted(signal.SIGINT)  # what a stage raises after Ctrl-C, its checkpoint saved

    monkeypatch.setattr(reproduce, "run_pipeline", interrupted_run)
    monkeypatch.chdir(REPO)
    demos = ["--demo", "data/demos/spade_00.npz", "--demo", "data/demos/spade_01.npz"]
    assert toolimit(["reproduce", *demos, "--out", str(tmp_path / "out"), "--quiet"]) == 130
    assert len(steps) == 1, "the second experiment started after the first was interrupted"
    assert "toolimit reproduce: interrupted (SIGINT)" in capsys.readouterr().err


def test_the_full_preset_measures_every_method_with_the_panda_and_the_pipeline_with_the_other_robots() -> None:
    from toolimit.experiments.reproduce import preset

    experiments = preset("full").experiments
    panda = [e for e in experiments if e.robot == "panda"]
    assert {e.tool for e in panda} == {"spade", "hammer", "scythe"}
    assert sum(e.tool == "spade" for e in panda) == 6
    assert all(e.methods == METHODS for e in panda if e.tool == "spade")
    for tool, demos in (("hammer", 6), ("scythe", 5)):  # five shipped demos, and the hammer's real recording
        timed = [e for e in panda if e.tool == tool]
        assert len(timed) == demos and len({e.demo for e in timed}) == demos
        assert [e.methods == METHODS for e in timed] == [e.demo.stem == f"{tool}_00" for e in timed]
        assert all(e.methods == ("tool_only", "trajopt", "final") for e in timed if e.demo.stem != f"{tool}_00")
    assert any(e.demo.name == "hammer_video1_aligned.npz" for e in panda)
    others = {e.robot: e.methods for e in experiments if e.robot != "panda"}
    assert others == {"ur5": ("tool_only", "trajopt", "final"), "talos": ("tool_only", "trajopt", "final")}


def test_jobs_run_experiments_in_child_processes_with_the_same_cells_as_one_process(
    quick_results: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "reproduce"
    monkeypatch.chdir(REPO)
    demos = ["--demo", "data/demos/spade_03.npz", "--demo", "data/demos/spade_01.npz"]
    methods = ["--methods", "tool_only,trajopt,final"]
    assert toolimit(["reproduce", "--preset", "quick", *demos, *methods, "--jobs", "2", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    for name in (EXPERIMENT, EXPERIMENT.replace("spade_03", "spade_01")):
        assert f"[{name}] ended (exit 0)" in said
        assert f"[{name}] [learning] started" in (out / "seed_0" / "logs" / f"{name}.log").read_text()
    for method in ("tool_only", "trajopt", "final"):
        key = f"{EXPERIMENT}-{method}.json"
        alone, in_child = (CellResult.load(folder / "seed_0" / "cells" / key) for folder in (quick_results, out))
        np.testing.assert_allclose(in_child.goal_rewards, alone.goal_rewards, rtol=1e-6, atol=1e-6)
        assert in_child.success_rate == alone.success_rate
    cells = json.loads((out / "results.json").read_text())["cells"]
    assert len(cells) == 6


def test_an_unknown_experiment_is_a_one_line_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert toolimit(["reproduce", "--experiment", "spade-3d-kuka-spade_00", "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and "unknown spade-3d-kuka-spade_00" in error and "spade-3d-ur5-" in error
    assert not (tmp_path / "out").exists()


def test_a_two_node_ray_cluster_measures_the_cells_of_a_local_run(
    quick_results: Path,
    loopback_ray_cluster: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Each kind of task once: the preparation (tool alone, trajectory), the method's learning run
    (final) and a baseline's (LfD: its kinesthetic demonstration, then cloning and PPO)."""
    out = tmp_path / "reproduce"
    monkeypatch.chdir(REPO)
    methods = ["--methods", "tool_only,trajopt,final,lfd"]
    assert toolimit(["reproduce", "--preset", "quick", *methods, "--ray", loopback_ray_cluster, "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "[cluster] Ray at 127.0.0.1:" in said and "2 Ray nodes, 2 CPUs" in said
    for method in ("tool_only", "trajopt", "final", "lfd"):
        assert re.search(rf"\] {method}: goal reward .* \(node 127\.0\.0\.1/\w+, \d+ s\)", said), said
        key = f"{EXPERIMENT}-{method}.json"
        alone, on_ray = (CellResult.load(folder / "seed_0" / "cells" / key) for folder in (quick_results, out))
        np.testing.assert_allclose(on_ray.goal_rewards, alone.goal_rewards, rtol=1e-6, atol=1e-6)
        assert (on_ray.success_rate, on_ray.env_steps) == (alone.success_rate, alone.env_steps)
    assert "/tmp/toolimit-task-" not in said  # the lines name the driver's folders
    experiment = out / "seed_0" / EXPERIMENT
    assert (experiment / "lfd" / "learning" / "policy.safetensors").is_file()  # the tasks' files came back
    assert (experiment / "method" / "evaluation.json").is_file()


def test_each_child_run_gets_its_share_of_the_cores_for_its_threads(monkeypatch):
    from toolimit.experiments.reproduce import child_environment

    monkeypatch.setattr("toolimit.experiments.reproduce.cores_given", lambda: 4)
    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    assert child_environment(2)["NUMBA_NUM_THREADS"] == "2"
    assert child_environment(8)["NUMBA_NUM_THREADS"] == "1"
    monkeypatch.setenv("NUMBA_NUM_THREADS", "3")
    assert child_environment(2)["NUMBA_NUM_THREADS"] == "3", "the user's own setting is kept"


def test_the_real_hammer_recording_aligns_with_its_wider_height_offset():
    """Its heights are not ground-referenced: the default z offset puts every sample's board off the
    ground, so the full preset gives that experiment, and only it, the README's 0.5 m."""
    from toolimit.experiments.reproduce import REAL_HAMMER_RECORDING, preset

    full = preset("full")
    offsets = {e.demo: full.settings(e, seed=0).align.search.z_offset_std for e in full.experiments}
    assert offsets.pop(REAL_HAMMER_RECORDING) == 0.5
    assert set(offsets.values()) == {PipelineSettings.for_world("3d").align.search.z_offset_std}


def test_every_learner_of_an_experiment_has_its_tools_budget():
    """The scythe's rows run at the scythe's own PPO cap (the authors' 14 M), the others at the 3D
    world's; the baselines learn with the method's settings (``measure_method``)."""
    from toolimit.experiments.reproduce import preset
    from toolimit.tools import tool_record

    full = preset("full")
    caps = {e.tool: full.settings(e, seed=0).learning.timesteps for e in full.experiments}
    assert caps["scythe"] == tool_record("scythe").settings["3d"]["learning.timesteps"]
    assert caps["spade"] == caps["hammer"] == PipelineSettings.for_world("3d").learning.timesteps
    assert preset("quick").settings(preset("quick").experiments[0], seed=0).learning.timesteps < 10_000


def test_the_full_figure_learns_within_the_robots_limits_and_its_variant_with_the_authors_span():
    """Every learner of the paper's figure within the robot's own limits (as the paper says its
    policies are); the variant as the authors' environment ran them: actions spanning 3 rad/s on
    every joint, the same experiments; the planar presets keep the arm's limits."""
    from toolimit.experiments.reproduce import preset

    full, span = preset("full"), preset("full-authors-span")
    assert {full.settings(e, seed=0).learning.action_limit for e in full.experiments} == {None}
    assert {span.settings(e, seed=0).learning.action_limit for e in span.experiments} == {3.0}
    assert span.experiments == full.experiments
    for name in ("quick", "planar"):
        chosen = preset(name)
        assert chosen.settings(chosen.experiments[0], seed=0).learning.action_limit is None


def test_results_of_another_seed_or_preset_are_not_taken_for_this_reproductions(quick_results, tmp_path, capsys):
    out = tmp_path / "figure"
    shutil.copytree(quick_results, out)
    shutil.copytree(out / "seed_0", out / "seed_1")  # a seed's folder holding another seed's results
    before = json.loads((quick_results / "results.json").read_text())
    for flags, path, said in (
        (["--preset", "planar"], out / "results.json", "another name (name 'quick', now 'planar')"),
        (["--preset", "quick", "--seed", "1"], out / "seed_1" / "results.json", "another seed (seed 0, now 1)"),
    ):
        with pytest.MonkeyPatch.context() as patch:
            patch.chdir(REPO)
            assert toolimit(["reproduce", *flags, "--out", str(out), "--quiet"]) == 2
        assert capsys.readouterr().err.strip().splitlines() == [
            f"toolimit reproduce: error: {path}: these results were made with {said}; choose another output folder"
        ]
        assert json.loads((out / "results.json").read_text()) == before, "nothing written"
    assert before["preset"] == {"name": "quick", "quick": True, "settings_changes": {}} and before["seeds"] == [0]
    seed_0 = json.loads((out / "seed_0" / "results.json").read_text())["preset"]
    assert seed_0 == {"name": "quick", "quick": True, "seed": 0, "settings_changes": {}}
