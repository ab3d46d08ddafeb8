"""Results (save/load, metrics) and replay in a scene (fake scene recording the tool poses)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from toolimit.artifacts import json_text
from toolimit.scenes import replay
from toolimit.scenes.base import ParameterSpec
from toolimit.tools import ToolPose
from toolimit.trajopt import SqpOptions, TrackOptions, TrajectoryResult, execute_in_scene, track
from toolimit.trajopt.execution import resample_joints
from toolimit.trajopt.result import TimeScaleSearch, TrackingStatistics

from trajopt_helpers import FPS, reachable_path, targets_of


@pytest.fixture(scope="module")
def planar_result(planar3):
    path = reachable_path(planar3, 16)
    targets = targets_of(planar3, path, np.array([0.2, 0.0, 0.0]))
    return targets, track(planar3, targets, TrackOptions(sqp=SqpOptions(max_iterations=10), q_start=path[0], starts=2))


def test_metrics_are_consistent(planar3, planar_result):
    targets, result = planar_result
    positions, _ = planar3.tool_poses(result.q[1:], result.base)
    np.testing.assert_allclose(result.position_error, np.linalg.norm(positions - targets.positions, axis=1))
    np.testing.assert_allclose(result.v, np.diff(result.q, axis=0) / result.dt)
    assert result.dt == pytest.approx(1 / FPS)
    assert result.limit_violations == 0 and result.velocity_violations == 0
    assert result.limit_margin.min() >= 0 and result.velocity_ratio.max() <= 1 + 1e-12
    summary = result.summary()
    assert summary["position_error_m"]["median"] == pytest.approx(np.median(result.position_error))
    assert summary["statistics"]["iterations"] >= 1


def test_save_load_round_trip(tmp_path, planar_result):
    _, result = planar_result
    result.save(tmp_path / "out")
    with np.load(tmp_path / "out" / "trajectory.npz") as arrays:
        assert set(arrays.files) == {"q", "v", "base", "joint_names", "dt"}
        assert arrays["joint_names"].tolist() == list(result.joint_names)
    document = json.loads((tmp_path / "out" / "trajectory.json").read_text())
    assert document["limit_violations"] == 0 and document["time_scale"] == 1.0
    loaded = TrajectoryResult.load(tmp_path / "out")
    for name in ("q", "v", "base", "position_error", "rotation_error", "limit_margin", "velocity_ratio"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(result, name))
    assert loaded.joint_names == result.joint_names and loaded.dt == result.dt
    assert loaded.statistics.cost == result.statistics.cost


def test_statistics_json_round_trip_and_older_files(planar_result):
    """The typed statistics survive their JSON form; a record of an older writer (with the time scale
    it no longer repeats) still reads."""
    _, result = planar_result
    search = TimeScaleSearch(median_position_error_m={1.0: 0.02, 1.5: 0.004}, threshold_m=0.01, threshold_met=True)
    statistics = dataclasses.replace(result.statistics, time_scale_search=search)
    record = json.loads(json_text(statistics.to_json()))
    assert record["time_scale_search"]["median_position_error_m"] == {"1": 0.02, "1.5": 0.004}
    assert TrackingStatistics.from_json(record) == statistics
    older = json.loads(json_text(result.statistics.to_json())) | {"time_scale": 1.0}
    assert "time_scale_search" not in older
    assert TrackingStatistics.from_json(older) == result.statistics


def test_failed_save_leaves_nothing(tmp_path, planar_result):
    _, result = planar_result
    broken = dataclasses.replace(
        result, statistics=dataclasses.replace(result.statistics, cost_terms={"not json": object()})
    )
    with pytest.raises(TypeError):
        broken.save(tmp_path / "out")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    with pytest.raises(FileNotFoundError, match="trajectory.npz"):
        TrajectoryResult.load(tmp_path / "out")


class RecordingScene:
    """A fake Scene: records the tool poses; reward = number of steps with the tool head below z = 0.4 m."""

    tool, world, control_dt, batch_size = "spade", "planar", 1 / FPS, 1
    parameters = (ParameterSpec("box", "position", (-1.0, -1.0, 0.0), (1.0, 1.0, 0.0)),)

    def __init__(self, footprint=(5.0, 0.0, 0.1, 0.1, 0.0)):
        self.footprint = np.array([footprint])

    def invalid_reason(self, params):
        return None

    def reset(self, params, rng, batch_size=1):
        self.batch_size, self.poses, self.low = batch_size, [], np.zeros(batch_size)

    def step(self, tool_pose: ToolPose):
        self.poses.append(tool_pose)
        self.low += np.asarray(tool_pose.position)[..., 2] < 0.4

    def goal_reward(self):
        return self.low.copy()

    def footprints(self, params):
        return self.footprint


def test_robot_replay_steps_the_scene_with_forward_kinematics(planar3, planar_result):
    targets, result = planar_result
    scene = RecordingScene()
    rewards = execute_in_scene(planar3, result, scene, {"box": np.zeros(3)}, np.random.default_rng(0), batch_size=3)
    assert rewards.shape == (3,)
    assert len(scene.poses) == len(result.q)
    expected = planar3.tool_poses(result.q, result.base)
    np.testing.assert_allclose([p.position for p in scene.poses], expected[0])
    np.testing.assert_allclose(rewards, np.sum(expected[0][:, 2] < 0.4))
    tool_only = replay(scene, {"box": np.zeros(3)}, np.random.default_rng(0), targets.poses)
    assert tool_only.shape == (1,) and tool_only[0] == np.sum(targets.positions[:, 2] < 0.4)


def test_replay_rejects_a_base_inside_an_element(planar3, planar_result):
    _, result = planar_result
    scene = RecordingScene(footprint=(result.base[0], 0.0, 0.2, 10.0, 0.0))
    with pytest.raises(ValueError, match=r"robot base at \(x=.*stands inside scene element 0"):
        execute_in_scene(planar3, result, scene, {"box": np.zeros(3)}, np.random.default_rng(0))


def test_slowed_trajectories_are_resampled_at_the_control_rate():
    q = np.array([[0.0], [1.0], [2.0]])
    np.testing.assert_allclose(resample_joints(q, 0.1, 0.05), [[0.0], [0.5], [1.0], [1.5], [2.0]])
    assert resample_joints(q, 0.1, 0.1) is q


def test_replay_in_the_planar_hammer_scene():
    """A real scene: a robot replay and a tool-only replay of the same motion give the same
    reward when the robot tracks it exactly; a base on the nail's board is refused."""
    from toolimit.robots import make_robot
    from toolimit.scenes.registry import make_scene

    arm = make_robot("planar3", tool="hammer")
    path = reachable_path(arm, 12)
    base = np.array([-0.3, 0.0, 0.0])
    targets = targets_of(arm, path, base)
    exact = TrajectoryResult(
        robot=arm.name, tool="hammer", joint_names=arm.joint_names, q=path, v=np.diff(path, axis=0) * FPS, base=base,
        dt=1 / FPS, time_scale=1.0, position_error=np.zeros(12), rotation_error=np.zeros(12),
        limit_margin=np.minimum(path - arm.lower, arm.upper - path), velocity_ratio=np.zeros((12, 3)),
    )
    scene = make_scene("hammer", "planar")
    params = {"nail_position": np.array([targets.positions[-1, 0], 0.0, 0.1])}
    robot_reward = execute_in_scene(arm, exact, scene, params, np.random.default_rng(0), batch_size=2)
    positions, rotations = arm.tool_poses(path, base)
    tool_reward = replay(scene, params, np.random.default_rng(0), ToolPose(positions, rotations), batch_size=2)
    assert robot_reward.shape == (2,)
    np.testing.assert_array_equal(robot_reward, tool_reward)
    on_board = {"nail_position": np.array([base[0], 0.0, 0.1])}
    with pytest.raises(ValueError, match="stands inside scene element"):
        execute_in_scene(arm, exact, scene, on_board, np.random.default_rng(0))


def test_a_result_turned_half_a_turn_is_described_as_upside_down():
    from toolimit.trajopt import TrajectoryResult

    horizon = 6
    def result(rotation_error):
        return TrajectoryResult(
            robot="planar3", tool="spade", joint_names=("a", "b", "c"), q=np.zeros((horizon + 1, 3)),
            v=np.zeros((horizon, 3)), base=np.zeros(3), dt=0.1, time_scale=1.0,
            position_error=np.full(horizon, 0.002), rotation_error=rotation_error,
            limit_margin=np.ones((horizon + 1, 3)), velocity_ratio=np.zeros((horizon, 3)),
        )
    flipped = result(np.full(horizon, np.pi))
    assert flipped.upside_down and flipped.summary()["upside_down"]
    assert "position error median 0.2 cm, rotation error median 180 deg" in flipped.describe()
    assert "UPSIDE DOWN" in flipped.describe()
    upright = result(np.r_[np.full(4, 0.1), np.full(2, np.pi)])  # two flipped steps of six: not upside down
    assert not upright.upside_down and "rotation error median 6 deg" in upright.describe()
    assert "UPSIDE" not in upright.describe()
