"""The LfD baseline's kinesthetic demonstration: a scripted motion tracked by the robot (the planar
arm's scoop; the Panda's hammer strikes, which it can follow only slower)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from toolimit.errors import BaseInsideFootprint, NoKinestheticDemonstration
from toolimit.learn import LearningTask, shipped_task
from toolimit.learn.kinesthetic import SELECTION_JSON, kinesthetic_task
from toolimit.learn.task import TASK_NPZ
from toolimit.scenes.registry import scripted_motion
from toolimit.tools import ToolPose
from toolimit.trajopt import TIME_SCALE_GRID, TrackingWeights, TrackOptions
from toolimit.trajopt.result import TRAJECTORY_JSON, TRAJECTORY_NPZ

OPTIONS = TrackOptions(weights=TrackingWeights(velocity=1e-4), starts=2)


@pytest.fixture(scope="module")
def demonstration(spade_task: LearningTask, tmp_path_factory: pytest.TempPathFactory) -> tuple[LearningTask, Path]:
    folder = tmp_path_factory.mktemp("lfd")
    return kinesthetic_task(spade_task, folder, OPTIONS, (1.0,), seed=0, replays=4), folder


def test_the_task_is_the_robots_in_the_same_scene(spade_task: LearningTask, demonstration) -> None:
    lfd, folder = demonstration
    assert (lfd.tool, lfd.world, lfd.robot, lfd.joint_names) == (
        spade_task.tool,
        spade_task.world,
        spade_task.robot,
        spade_task.joint_names,
    )
    assert lfd.params.keys() == spade_task.params.keys()
    for name, value in spade_task.params.items():
        np.testing.assert_array_equal(lfd.params[name], value)
    assert lfd.reference_steps <= lfd.horizon <= 2 * lfd.reference_steps
    assert lfd.source["kinesthetic"] == str(folder)
    assert {path.name for path in folder.iterdir()} == {TRAJECTORY_NPZ, TRAJECTORY_JSON, SELECTION_JSON, TASK_NPZ}


def test_the_scripted_scoop_and_the_robots_replay_deliver(demonstration) -> None:
    _, folder = demonstration
    record = json.loads((folder / SELECTION_JSON).read_text())["candidates"][0]
    assert record["alignment_reward"] >= 10, "the scripted scoop alone fills the box"
    assert record["robot_reward"] >= 10, "the robot tracking it too"


def test_a_finished_demonstration_is_read_back_not_redone(spade_task: LearningTask, demonstration) -> None:
    lfd, folder = demonstration
    stamp = (folder / TASK_NPZ).stat().st_mtime_ns
    again = kinesthetic_task(spade_task, folder, OPTIONS, (1.0,), seed=0, replays=4)
    assert (folder / TASK_NPZ).stat().st_mtime_ns == stamp
    np.testing.assert_array_equal(again.reference_q, lfd.reference_q)


def test_a_robot_that_cannot_stand_anywhere_is_refused(
    spade_task: LearningTask, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every base the solver finds inside a scene element: BaseInsideFootprint, nothing written."""
    from toolimit.scenes.planar.spade import PlanarSpadeScene

    everywhere = np.array([[0.0, 0.0, 100.0, 100.0, 0.0]])
    monkeypatch.setattr(PlanarSpadeScene, "footprints", lambda self, params: everywhere)
    with pytest.raises(BaseInsideFootprint, match="cannot track the scripted spade motion"):
        kinesthetic_task(spade_task, tmp_path / "lfd", OPTIONS, (1.0,), seed=0, replays=1)
    assert not (tmp_path / "lfd").exists()


def test_an_arm_too_slow_for_the_strike_demonstrates_it_slower(tmp_path: Path) -> None:
    """At real time the Panda cannot follow the scripted 2 m/s strikes; a person guiding it would
    slow down until it plants the nail: the first slower pace whose replay earns is kept."""
    hammer = shipped_task("hammer", "3d")
    lfd = kinesthetic_task(hammer, tmp_path / "lfd", OPTIONS, (1.0,), seed=0, replays=2)
    record = json.loads((tmp_path / "lfd" / SELECTION_JSON).read_text())["candidates"][0]
    by_scale = {float(scale): reward for scale, reward in record["robot_reward_by_time_scale"].items()}
    assert by_scale[1.0] == 0.0, "the premise: at real time the arm plants no nail"
    assert record["robot_reward"] > 0
    assert record["time_scale"] > 1.0 and by_scale[record["time_scale"]] == record["robot_reward"]
    assert list(by_scale) == [scale for scale in TIME_SCALE_GRID if scale <= record["time_scale"]]
    assert all(reward == 0.0 for scale, reward in by_scale.items() if scale < record["time_scale"])
    assert lfd.horizon > record["time_scale"] * len(scripted_motion("hammer", "3d", hammer.params)) / 2


def test_the_panda_follows_the_scripted_scythe_draw_within_its_limits(tmp_path: Path) -> None:
    """The draw along the patch (1.5 m/s after a run-up) asks more acceleration than the Panda has:
    within its limits the arm follows it at real time or a little slower and still cuts stalks in
    the shipped task's replays (the earlier pulls, their handle end held below the blade, cut
    nothing at any pace)."""
    lfd = kinesthetic_task(shipped_task("scythe", "3d"), tmp_path / "lfd", OPTIONS, (1.0,), seed=0, replays=2)
    record = json.loads((tmp_path / "lfd" / SELECTION_JSON).read_text())["candidates"][0]
    by_scale = {float(scale): reward for scale, reward in record["robot_reward_by_time_scale"].items()}
    assert record["time_scale"] <= 1.5 and record["robot_reward"] > 0
    assert all(reward == 0.0 for scale, reward in by_scale.items() if scale < record["time_scale"])
    assert lfd.tool == "scythe"


def test_a_motion_the_robot_earns_nothing_with_at_any_pace_is_refused(
    spade_task: LearningTask, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A spade held still above the deposit delivers nothing, however slowly the arm follows it:
    NoKinestheticDemonstration naming every pace tried, nothing written."""

    def held_still(tool: str, world: str, params: dict, fps: float) -> ToolPose:
        start = scripted_motion(tool, world, params, fps=fps)
        return ToolPose(np.repeat(start.position[:1], 24, axis=0), np.repeat(start.rotation[:1], 24, axis=0))

    monkeypatch.setattr("toolimit.learn.kinesthetic.scripted_motion", held_still)
    paces = ", ".join(f"{scale:g}" for scale in TIME_SCALE_GRID)
    with pytest.raises(NoKinestheticDemonstration, match=f"earns nothing at time scales {paces}: "):
        kinesthetic_task(spade_task, tmp_path / "lfd", OPTIONS, (1.0,), seed=0, replays=1)
    assert not (tmp_path / "lfd").exists()
