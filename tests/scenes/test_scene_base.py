"""The scene helpers every scene shares: the spec-driven parameter check and the success tests."""

import numpy as np
import pytest

from toolimit.scenes.base import (
    WORLD_HALF_SIZE,
    GoalTimer,
    ParameterSpec,
    SceneBase,
    SuccessTracker,
    WindowedGoalScene,
    dense_hammer_reward,
    dense_scythe_reward,
    dense_spade_reward,
    dense_tool_point,
    parameter_violation,
    world_position,
)

SPECS = (
    ParameterSpec("box", "position", (-WORLD_HALF_SIZE, -WORLD_HALF_SIZE, 0.1), (WORLD_HALF_SIZE,) * 2 + (2.0,),
                  axes=(0, 2), bound_reason="the box stands above the floor"),
    ParameterSpec("yaw", "uniform", -np.pi, np.pi),
)
GOOD = {"box": np.array([1.0, 9.0, 0.5]), "yaw": 0.3}  # y is not one of the checked axes


@pytest.mark.parametrize(("change", "message"), [
    ({}, None),
    ({"box": np.array([6.0, 0.0, 0.5])}, "box x = 6.000 m is outside the world bound [-5, 5] m (the box stands"),
    ({"box": np.array([0.0, 0.0, 0.0])}, "box z = 0.000 m is outside the world bound [0.1, 2] m"),
    ({"box": np.array([0.0, np.nan, 0.5])}, "must be a finite (3,) world point"),
    ({"box": np.zeros(2)}, "of shape (2,)"),
    ({"yaw": 4.0}, "yaw must be a number in [-3.142, 3.142], got 4.0"),
])
def test_parameter_violation_names_the_parameter_the_axis_and_the_bound(change, message):
    reason = parameter_violation(SPECS, {**GOOD, **change})
    assert reason is None if message is None else message in reason


def test_world_position_spans_the_world_in_x_y_and_stands_on_the_ground_unless_raised():
    ground = world_position("box", "a box", axes=(0, 1))
    assert ground == ParameterSpec("box", "position", (-WORLD_HALF_SIZE, -WORLD_HALF_SIZE, 0.0),
                                   (WORLD_HALF_SIZE, WORLD_HALF_SIZE, 0.0), on_ground=True, unit="m",
                                   description="a box", axes=(0, 1))
    raised = world_position("box", "a box", low_z=0.1, high_z=2.0, axes=(0, 2), bound_reason="above the floor")
    assert not raised.on_ground and raised.low == SPECS[0].low and raised.high == SPECS[0].high


def test_parameter_violation_names_a_missing_parameter():
    assert parameter_violation(SPECS, {"yaw": 0.0}) == "missing parameter 'box'"


def test_success_tracker_needs_the_goal_on_half_of_the_steps():
    tracker = SuccessTracker(batch_size=2)
    assert not tracker.is_success().any()
    for met in ([True, False], [False, False], [True, True], [False, False]):
        tracker.record(np.array(met))
    assert tracker.is_success().tolist() == [True, False]  # 2 of 4 steps, 1 of 4 steps


def test_goal_timer_keeps_the_first_time_the_goal_was_met():
    timer = GoalTimer(batch_size=3)
    assert not timer.within(1.0).any()
    for met in ([False, True, False], [True, True, False], [True, False, False]):
        timer.advance(0.5)
        timer.record(np.array(met))
    timer.record(np.array([True, True, True]), at=np.array([0.1, 0.1, 1.25]))  # times given: the third is new
    assert timer.time == 1.5 and timer.met_at.tolist() == [1.0, 0.5, 1.25]
    assert timer.within(1.0).tolist() == [True, True, False]


def test_scene_base_checks_the_timing_and_the_parameters_against_the_specs():
    with pytest.raises(ValueError, match="control_dt must be a positive number"):
        SceneBase(control_dt=0.0, substeps=10)
    with pytest.raises(ValueError, match="substeps must be >= 1"):
        SceneBase(control_dt=0.04, substeps=0)
    scene = SceneBase(control_dt=0.04, substeps=10)
    scene.parameters = SPECS
    assert (scene.control_dt, scene.substeps, scene.batch_size) == (0.04, 10, 0)
    assert scene.invalid_reason(GOOD) is None
    assert scene.invalid_reason({"yaw": 0.0}) == "missing parameter 'box'"


def test_windowed_goal_scene_succeeds_within_its_window_after_a_reset():
    scene = WindowedGoalScene(control_dt=0.04, substeps=10, success_window=0.5)
    with pytest.raises(RuntimeError, match="call reset"):
        scene.is_success()
    scene.start_instances(2)
    scene.goal_timer.advance(0.4)
    scene.goal_timer.record(np.array([True, False]))
    scene.goal_timer.advance(0.4)
    scene.goal_timer.record(np.array([True, True]))
    assert scene.batch_size == 2 and scene.is_success().tolist() == [True, False]


def test_dense_rewards_are_the_appendix_closeness_terms():
    origin, far = np.zeros((2, 3)), np.full((2, 3), 100.0)
    assert dense_hammer_reward(None, far).tolist() == [0.0, 0.0]
    assert dense_hammer_reward(origin, origin).tolist() == [1.0, 1.0]
    patch = np.zeros((2, 3))
    assert dense_scythe_reward(None, patch).tolist() == [0.0, 0.0]
    np.testing.assert_allclose(dense_scythe_reward(origin, patch), 0.1)
    np.testing.assert_allclose(dense_scythe_reward(np.array([[0.0, 0.0, 0.3]] * 2), patch), 0.1 * np.exp(-5 * 0.09))
    grains, goal = np.zeros((2, 4, 2)), np.zeros((2, 1, 2))
    np.testing.assert_allclose(dense_spade_reward(grains, goal, None, np.zeros(2)), 1.0)
    np.testing.assert_allclose(dense_spade_reward(grains, goal, np.zeros((2, 2)), np.zeros(2)), 1.05)


def test_dense_tool_points_are_the_authors():
    """pyphysx_envs: the spade's body origin (the handle end), the hammer's tip (the striking face),
    the scythe's tip (the head point)."""
    np.testing.assert_allclose(dense_tool_point("spade"), [0.0, 0.0, 0.40])
    np.testing.assert_allclose(dense_tool_point("hammer"), [0.055, 0.0, 0.0])
    np.testing.assert_allclose(dense_tool_point("scythe"), [0.0, 0.0, 0.0])
