"""The Gymnasium environments: check_env on every id, the paper's observation, action and reward."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import toolimit.learn  # noqa: F401  (registers the ids)
import toolimit.learn.simulator as simulator_module
from toolimit.learn import TaskSimulator, shipped_task
from toolimit.learn.env import ENV_TOOLS, ENV_WORLDS, ToolUseEnv, env_id
from toolimit.learn.shipped import environments
from toolimit.learn.simulator import PARAM_NOISE_STD, velocity_penalty

IDS = [env_id(tool, world) for tool, world in environments()]


def test_the_built_in_tools_have_an_id_in_both_worlds():
    assert set(IDS) == {env_id(tool, world) for tool in ("spade", "hammer", "scythe") for world in ENV_WORLDS}
    assert tuple(ENV_TOOLS) == ("spade", "hammer", "scythe")


@pytest.mark.parametrize("name", IDS)
def test_check_env_passes_on_every_registered_id(name):
    env = gym.make(name)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.action_space.low.min() == -1.0 and env.action_space.high.max() == 1.0
    n = len(env.unwrapped.task.joint_names)
    assert env.observation_space.shape == (3 + 4 + n + 1,)


def test_unknown_id_is_gymnasiums_error():
    with pytest.raises(gym.error.Error):
        gym.make("toolimit/Shovel3D-v0")


def test_episode_truncates_at_the_horizon_and_reports_success(spade_task):
    env = ToolUseEnv("spade", "planar", task=spade_task)
    observation, _ = env.reset(seed=3)
    assert observation[-1] == 0.0
    for t in range(1, spade_task.horizon + 1):
        observation, reward, terminated, truncated, info = env.step(env.tracking_action())
        assert not terminated and truncated == (t == spade_task.horizon)
        assert np.isclose(observation[-1], t * spade_task.control_dt)  # seconds, as the authors
        assert env.observation_space.contains(observation)
    assert info["is_success"] is True and info["goal_reward"] >= 10


def test_observation_is_tool_pose_joints_and_time(spade_task):
    env = ToolUseEnv("spade", "planar", task=spade_task)
    observation, _ = env.reset(seed=0)
    simulator = env.simulator
    position, rotation = simulator.robot.tool_pose(simulator.q[0], spade_task.base)
    np.testing.assert_allclose(observation[:3], position, atol=1e-6)
    quaternion = observation[3:7].astype(float)
    assert np.isclose(np.linalg.norm(quaternion), 1.0, atol=1e-6)
    np.testing.assert_allclose(observation[7:-1], simulator.q[0], atol=1e-6)
    assert np.max(np.abs(simulator.q[0] - spade_task.reference_q[0])) < 0.05  # N(0, 0.01) rad noise


def test_action_is_a_fraction_of_the_velocity_limit_and_joints_stay_in_limits(spade_task):
    env = ToolUseEnv("spade", "planar", task=spade_task)
    env.reset(seed=0)
    simulator = env.simulator
    before = simulator.q[0].copy()
    env.step(np.full(simulator.n_joints, 0.5, dtype=np.float32))
    expected = np.clip(before + 0.5 * simulator.robot.velocity_limit * simulator.dt, simulator.robot.lower,
                       simulator.robot.upper)
    np.testing.assert_allclose(simulator.q[0], expected)
    for _ in range(60):
        env.step(np.ones(simulator.n_joints, dtype=np.float32))
    assert np.all(simulator.q[0] <= simulator.robot.upper + 1e-12)


def test_an_action_limit_scales_the_action_and_the_penalty_stays_at_the_robots_limits(spade_task):
    """The authors' clip (3 rad/s on every joint): an action of 1 commands 3 rad/s, beyond the
    robot's limits, and is penalised above 0.9 of the robot's own limits; the tracking controller
    commands the same velocities, clipped at the action limit instead of the robot's."""
    authors = TaskSimulator(dataclasses.replace(spade_task, action_limit=3.0), batch_size=2)
    plain = TaskSimulator(spade_task, batch_size=2)
    limit = authors.robot.velocity_limit
    assert np.all(limit < 3.0) and np.array_equal(plain.action_scale, limit)
    np.testing.assert_array_equal(authors.action_scale, np.full(authors.n_joints, 3.0))
    for simulator in (authors, plain):
        simulator.reset(np.random.default_rng(0))
    commanded = authors.tracking_action() * 3.0  # rad/s; the robot's limits clip more of it
    np.testing.assert_allclose(np.clip(commanded, -limit, limit), plain.tracking_action() * limit)
    before = authors.q.copy()
    _, reward, goal = authors.step(np.full((2, authors.n_joints), 0.1))
    np.testing.assert_allclose(authors.q, np.clip(before + 0.3 * authors.dt, authors.robot.lower, authors.robot.upper))
    np.testing.assert_allclose(reward * authors.horizon, goal, err_msg="0.3 rad/s is far below 0.9 of the limits")
    _, reward, goal = authors.step(np.ones((2, authors.n_joints)))
    penalty = velocity_penalty(np.full((2, authors.n_joints), 3.0), limit)
    assert np.all(penalty < 0)
    np.testing.assert_allclose(reward * authors.horizon, goal + penalty)


def test_velocity_penalty_only_above_ninety_percent_of_the_limit():
    limit = np.array([2.0, 1.0])
    assert velocity_penalty(np.array([[1.8, -0.9]]), limit)[0] == 0.0
    assert np.isclose(velocity_penalty(np.array([[2.0, 0.0]]), limit)[0], -0.01 * 0.2)
    assert np.isclose(velocity_penalty(np.array([[0.0, -1.0]]), limit)[0], -0.01 * 0.1)


def test_same_seed_same_episode(spade_task):
    def rollout(seed):
        env = ToolUseEnv("spade", "planar", task=spade_task)
        observations = [env.reset(seed=seed)[0]]
        for _ in range(30):
            observations.append(env.step(env.tracking_action())[0])
        return np.array(observations)

    np.testing.assert_array_equal(rollout(5), rollout(5))
    assert not np.array_equal(rollout(5), rollout(6))


def test_a_task_of_another_world_is_refused(spade_task):
    with pytest.raises(ValueError, match="the task is the spade in planar, not the spade in 3d"):
        ToolUseEnv("spade", "3d", task=spade_task)


def test_dense_reward_adds_the_scenes_shaping_to_the_goal_reward(spade_task):
    sparse = ToolUseEnv("spade", "planar", task=spade_task)
    dense = ToolUseEnv("spade", "planar", task=spade_task, reward="dense")
    sparse.reset(seed=4)
    dense.reset(seed=4)
    for _ in range(40):
        _, sparse_reward, _, _, sparse_info = sparse.step(sparse.tracking_action())
        _, dense_reward, _, _, dense_info = dense.step(dense.tracking_action())
        shaping = float(dense.simulator.scene.dense_reward()[0]) / spade_task.horizon
        assert dense_reward == pytest.approx(sparse_reward + shaping, abs=1e-12)
        assert dense_info["goal_reward"] == sparse_info["goal_reward"]  # same episode, same sand


def test_an_unknown_reward_is_refused(spade_task):
    with pytest.raises(ValueError, match="unknown reward 'shaped'; choose one of sparse, dense"):
        ToolUseEnv("spade", "planar", task=spade_task, reward="shaped")



SCENE_POSITIONS = {  # tool, world: the scene's state holding each instance's position parameters, m
    ("spade", "planar"): lambda scene: np.column_stack([scene.sand_x, scene.goal_x]),
    ("spade", "3d"): lambda scene: np.column_stack([scene.sand_position[:, :2], scene.goal_position[:, :2]]),
    ("hammer", "3d"): lambda scene: scene._nail_xy,
    ("scythe", "3d"): lambda scene: scene.grass_position[:, :2],
    ("scythe", "planar"): lambda scene: scene.grass_centre,
}


def scene_offsets(simulator: TaskSimulator) -> np.ndarray:
    """(B, K) each instance's scene positions minus the task's exact ones, m."""
    tool, world = simulator.task.tool, simulator.task.world
    exact = simulator.copy(batch_size=1).scene
    exact.reset(simulator.task.params, np.random.default_rng(0), 1)
    return SCENE_POSITIONS[tool, world](simulator.scene) - SCENE_POSITIONS[tool, world](exact)


@pytest.mark.parametrize(("tool", "world"), SCENE_POSITIONS, ids=[f"{tool}-{world}" for tool, world in SCENE_POSITIONS])
def test_reset_noise_moves_every_instance_s_positions_by_its_own_draw(tool, world):
    """Each instance's scene positions take their own N(0, 1 cm) draw (the authors' environments
    each drew their own): 16 instances, all offsets within 5 standard deviations, all different
    but those of the instances whose draw was invalid (exact positions: the planar spade's deposit
    stands 5 mm from the box's clearance, so about 40 % of its draws push it in)."""
    scene_kwargs = {"n_spheres": 20} if (tool, world) == ("spade", "3d") else None
    simulator = TaskSimulator(shipped_task(tool, world), batch_size=16, scene_kwargs=scene_kwargs)
    simulator.reset(np.random.default_rng(3))
    offsets = scene_offsets(simulator)
    assert np.all(np.abs(offsets) < 5 * PARAM_NOISE_STD)
    moved = offsets[np.any(offsets != 0.0, axis=1)]
    assert len(np.unique(moved.round(9), axis=0)) == len(moved) >= 8


def test_an_instance_whose_noise_makes_its_scene_invalid_keeps_the_exact_positions(spade_task, monkeypatch):
    """With 0.3 m noise some deposits run into their boxes: those instances, and only they, keep
    the task's positions."""
    monkeypatch.setattr(simulator_module, "PARAM_NOISE_STD", 0.3)
    simulator = TaskSimulator(spade_task, batch_size=32)
    simulator.reset(np.random.default_rng(0))
    exact = np.all(scene_offsets(simulator) == 0.0, axis=1)
    assert 0 < exact.sum() < 32
    scene, params = simulator.scene, dict(spade_task.params)
    for sand_x, goal_x, kept in zip(scene.sand_x, scene.goal_x, exact):
        moved = params | {"sand_position": np.array([sand_x, 0.0, 0.0]), "goal_position": np.array([goal_x, 0.0, 0.0])}
        assert kept or scene.invalid_reason(moved) is None
