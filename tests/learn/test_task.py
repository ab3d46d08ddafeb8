"""LearningTask: saved and loaded by value, clear errors for bad files, a horizon that allows success."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from toolimit.learn import LearningTask, TaskFileError, shipped_task, shipped_tasks
from toolimit.learn.task import success_horizon
from toolimit.robots import make_robot
from toolimit.scenes.registry import make_scene


def test_save_and_load_round_trip(spade_task, tmp_path):
    path = spade_task.save(tmp_path / "task.npz")
    loaded = LearningTask.load(tmp_path)  # a folder reads its task.npz
    assert (loaded.tool, loaded.world, loaded.robot) == (spade_task.tool, spade_task.world, spade_task.robot)
    assert loaded.joint_names == spade_task.joint_names and loaded.horizon == spade_task.horizon
    np.testing.assert_array_equal(loaded.reference_q, spade_task.reference_q)
    np.testing.assert_array_equal(loaded.base, spade_task.base)
    assert set(loaded.params) == set(spade_task.params)
    for name, value in spade_task.params.items():
        np.testing.assert_array_equal(loaded.params[name], value)
    assert path.is_file()


def test_load_names_the_problem(spade_task, tmp_path):
    with pytest.raises(TaskFileError, match="no such task file"):
        LearningTask.load(tmp_path / "absent.npz")
    (tmp_path / "junk.npz").write_text("not a zip")
    with pytest.raises(TaskFileError, match="junk.npz: not a task file"):
        LearningTask.load(tmp_path / "junk.npz")
    np.savez(tmp_path / "partial.npz", tool="spade")
    with pytest.raises(TaskFileError, match="missing keys"):
        LearningTask.load(tmp_path / "partial.npz")


def test_the_action_limit_is_saved_and_checked(spade_task, tmp_path):
    assert LearningTask.load(spade_task.save(tmp_path / "robot.npz")).action_limit is None
    authors = dataclasses.replace(spade_task, action_limit=3.0)
    assert LearningTask.load(authors.save(tmp_path / "authors.npz")).action_limit == 3.0
    arrays = dict(np.load(tmp_path / "authors.npz")) | {"action_limit": np.float64(0.0)}
    np.savez(tmp_path / "zero.npz", **arrays)
    with pytest.raises(TaskFileError) as refused:
        LearningTask.load(tmp_path / "zero.npz")
    assert str(refused.value) == f"{tmp_path / 'zero.npz'}: action_limit must be a finite number > 0 (rad/s), got 0.0"


def test_every_registered_pair_has_a_shipped_task():
    shipped = {(tool, world) for tool, world, _ in shipped_tasks()}
    assert shipped == {(t, w) for t in ("spade", "hammer", "scythe") for w in ("planar", "3d")}


def test_unknown_shipped_task_lists_the_known_ones():
    with pytest.raises(ValueError, match="no shipped task .* robot ur5; shipped: .*spade/planar/planar3"):
        shipped_task("spade", "planar", robot="ur5")


def test_horizon_covers_the_reference_and_lets_the_reference_succeed(spade_task):
    """The shipped spade's reference succeeds within its horizon (measured, not assumed)."""
    assert spade_task.reference_steps <= spade_task.horizon <= 2 * spade_task.reference_steps
    robot, scene = make_robot(spade_task.robot, spade_task.tool), make_scene("spade", "planar")
    horizon = success_horizon(robot, scene, spade_task.params, spade_task.base, spade_task.reference_q,
                              np.random.default_rng(0))
    assert horizon == spade_task.horizon
    assert bool(scene.is_success()[0])
