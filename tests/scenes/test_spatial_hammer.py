"""Physics of the 3D hammer world: momentum-model travel, no tunnelling, range, success window."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.scenes.base import InvalidSceneParameters, Scene
from toolimit.scenes.registry import make_scene
from toolimit.scenes.spatial.hammer import SpatialHammerScene
from toolimit.scenes.spatial.strike import FACE_OFFSET, face_down, face_poses, strike_descent
from toolimit.tools import ToolPose

NAIL = np.array([0.5, 0.2, 0.3])
#: Hammer face down: tool x (striking direction) = -world z, tool z (handle) = world y.
FACE_DOWN = face_down(np.array([0.0, 1.0, 0.0]))


def strike(scene, speed, overshoot=0.002, offset=(0.0, 0.0), approach_steps=6, hold_steps=12, top=None):
    """Lower the face at ``speed`` (m/s) to ``overshoot`` below the nail top, then lift it away.

    The last descending control step ends ``overshoot`` below the current nail top; the nail then
    glides from the face's speed. Returns the nail travel during the strike (m), instance 0.
    """
    start = scene.nail_top[0] if top is None else top
    xy = NAIL[:2] + np.asarray(offset)
    descent = strike_descent(xy, start - overshoot, speed, approach_steps, scene.control_dt, FACE_DOWN)
    away = face_poses(xy, np.full(hold_steps, start + 0.1), FACE_DOWN)
    for poses in (descent, away):
        for position, rotation in zip(*poses):
            scene.step(ToolPose(position, rotation))
    return start - scene.nail_top[0]


def fresh(batch_size=1, **kwargs):
    scene = SpatialHammerScene(**kwargs)
    scene.reset({"nail_position": NAIL}, np.random.default_rng(0), batch_size=batch_size)
    return scene


def test_registry_and_protocol():
    scene = make_scene("hammer", "3d")
    assert isinstance(scene, Scene)
    assert scene.parameters[0].name == "nail_position" and scene.parameters[0].on_ground is False


@pytest.mark.parametrize("speed", [0.5, 1.0, 2.0, 2.8])
@pytest.mark.parametrize("restitution", [0.0, 0.3])
def test_travel_matches_momentum_model(speed, restitution):
    scene = fresh(restitution=restitution, protrusion=0.09)
    overshoot = 0.002
    travel = strike(scene, speed, overshoot=overshoot)
    expected = overshoot + ((1 + restitution) * speed) ** 2 / (2 * scene.entry_deceleration)
    assert expected < scene.protrusion, "test speeds must stay below the board"
    assert travel == pytest.approx(expected, abs=5e-4), f"travel {travel * 1000:.2f} mm, model {expected * 1000:.2f} mm"


def test_weak_tap_moves_a_little_full_strike_several_centimetres():
    tap = strike(fresh(), 0.3)
    full = strike(fresh(), 3.0)
    assert 0.0 < tap < 0.005
    assert full > 0.03
    assert tap < full


@pytest.mark.parametrize("substeps", [1, 10])
def test_no_tunnelling_at_4_m_per_s(substeps):
    """One control step takes the face from 8 cm above the nail head to 8 cm below it."""
    scene = fresh(substeps=substeps)
    scene.step(ToolPose(NAIL + [0.0, 0.0, 0.08 + FACE_OFFSET], FACE_DOWN))
    scene.step(ToolPose(NAIL + [0.0, 0.0, -0.0867 + FACE_OFFSET], FACE_DOWN))
    assert scene.nail_speed[0] > 0 or scene.remaining_depth()[0] < scene.protrusion
    assert NAIL[2] - scene.nail_top[0] > 0.05 - 1e-9  # pushed to the board at once (0.0867 m > 0.05 m)
    assert scene.goal_reward()[0] == 1.0


def test_nail_never_leaves_its_travel_range():
    scene = fresh()
    tops = []
    for _ in range(5):
        strike(scene, 4.0, overshoot=0.03)
        tops.append(scene.nail_top[0])
    assert np.all(np.diff(tops) <= 0)
    assert np.min(tops) == pytest.approx(scene.lowest_top)
    assert np.all(scene.remaining_depth() >= 0.0)


def test_scripted_strikes_plant_the_nail_within_the_window():
    scene = fresh()
    travels = [strike(scene, 2.5, approach_steps=3, hold_steps=2) for _ in range(3)]
    assert travels[0] > 0.02
    assert scene.goal_reward()[0] == 1.0
    assert scene.is_success()[0]
    assert scene.remaining_depth()[0] < scene.planted_tolerance


def test_planting_after_the_window_is_not_a_success():
    late, early = fresh(), fresh()
    strike(late, 0.5, hold_steps=30)  # a tap, then more than a second of nothing
    strike(late, 4.0, overshoot=0.03)
    strike(early, 4.0, overshoot=0.03)
    assert late.goal_reward()[0] == early.goal_reward()[0] == 1.0
    assert late.goal_timer.met_at[0] > late.success_window and not late.is_success()[0]
    assert early.goal_timer.met_at[0] < early.success_window and early.is_success()[0]


def test_striking_beside_the_nail_does_nothing():
    scene = fresh()
    # The face (3 cm across y) passes 2 cm beyond the plate's edge (3 cm half size).
    travel = strike(scene, 4.0, overshoot=0.04, offset=(0.0, 0.03 + 0.015 + 0.02))
    assert travel == 0.0
    assert scene.goal_reward()[0] == 0.0 and scene.nail_speed[0] == 0.0


def test_first_step_places_the_tool_without_velocity():
    scene = fresh()
    scene.step(ToolPose(NAIL + [0.0, 0.0, -0.02 + FACE_OFFSET], FACE_DOWN))  # placed overlapping the head
    assert scene.nail_top[0] == NAIL[2]
    scene.step(ToolPose(NAIL + [0.0, 0.0, 0.2], FACE_DOWN))  # leaving upwards does not pull or push
    assert scene.nail_top[0] == NAIL[2]


def test_batched_instances_are_independent_and_deterministic():
    poses_z = np.array([0.08, 0.08, 0.08]) + NAIL[2] + FACE_OFFSET
    xy = np.array([NAIL[:2], NAIL[:2] + [0.2, 0.0], NAIL[:2]])
    rewards = []
    for _ in range(2):
        scene = fresh(batch_size=3)
        for k in range(8):
            z = poses_z - k * 3.0 * scene.control_dt
            scene.step(ToolPose(np.column_stack([xy, z]), np.broadcast_to(FACE_DOWN, (3, 3, 3))))
        rewards.append((scene.goal_reward(), scene.dense_reward(), scene.nail_top.copy()))
    top = rewards[0][2]
    assert top[0] == top[2] and top[1] == NAIL[2] and top[0] < NAIL[2]
    for a, b in zip(*rewards):
        np.testing.assert_array_equal(a, b)


def test_dense_reward_is_the_closeness_of_the_face_to_the_nail_head_where_it_is_now():
    """exp(-5 d^2), d from the striking face (the authors' hammer tip) to the nail head's centre
    (their nail body's origin); 0 unplaced."""
    scene = fresh()
    assert scene.dense_reward()[0] == 0.0  # no hammer yet
    half_plate = scene.plate_thickness / 2
    scene.step(ToolPose(NAIL + [0.0, 0.0, 0.5], FACE_DOWN))
    far = scene.dense_reward()[0]
    scene.step(ToolPose(NAIL + [0.0, 0.0, 0.1], FACE_DOWN))
    near = scene.dense_reward()[0]
    assert far == pytest.approx(np.exp(-5.0 * (0.5 - FACE_OFFSET + half_plate) ** 2))
    assert near == pytest.approx(np.exp(-5.0 * (0.1 - FACE_OFFSET + half_plate) ** 2))
    assert 0.0 < far < near <= 1.0
    travel = strike(scene, 3.0)
    assert travel > 0.01
    offset = np.array([0.1, -0.2, 0.3])  # of the face from the driven nail's head centre
    centre = np.array([*NAIL[:2], scene.nail_top[0] - half_plate])
    scene.step(ToolPose(centre + offset + [0.0, 0.0, FACE_OFFSET], FACE_DOWN))
    assert scene.dense_reward()[0] == pytest.approx(np.exp(-5.0 * np.sum(offset**2)))


def test_invalid_parameters_are_rejected_with_a_reason():
    scene = SpatialHammerScene()
    assert scene.invalid_reason({"nail_position": NAIL}) is None
    assert "shape" in scene.invalid_reason({"nail_position": np.zeros(2)})
    assert "outside" in scene.invalid_reason({"nail_position": np.array([0.0, 0.0, 0.03])})
    assert "missing" in scene.invalid_reason({})
    with pytest.raises(InvalidSceneParameters, match="outside"):
        scene.reset({"nail_position": np.array([0.0, 0.0, 0.0])}, np.random.default_rng(0))
    with pytest.raises(ValueError, match="protrusion"):
        SpatialHammerScene(protrusion=0.2)


def test_footprint_and_snapshot():
    scene = fresh()
    np.testing.assert_allclose(scene.footprints({"nail_position": NAIL}), [[0.5, 0.2, 0.15, 0.15, 0.0]])
    snap = scene.snapshot()
    assert np.isnan(snap["tool_position"]).all()
    assert snap["board_center"][2] * 2 == pytest.approx(NAIL[2] - 0.06)
    strike(scene, 3.0)
    snap = scene.snapshot()
    assert snap["nail_top"][2] == scene.nail_top[0]
    assert np.isfinite(snap["tool_rotation"]).all()


def test_skipping_idle_steps_changes_nothing():
    """The shortcut for steps far from the nail gives the same nail motion as full sub-stepping."""
    rng = np.random.default_rng(3)
    path = NAIL + FACE_OFFSET * np.array([0.0, 0.0, 1.0]) + rng.normal(0.0, 0.06, size=(60, 3))
    path[::7, 2] += 0.15  # lifts between strikes; rotations vary too
    rotations = FACE_DOWN @ np.stack([rotation_about_y(a) for a in rng.normal(0.0, 0.2, size=60)])
    tops = []
    for always in (False, True):
        scene = fresh(batch_size=2)
        if always:
            scene._may_interact = lambda points: True
        for p, r in zip(path, rotations):
            scene.step(ToolPose(np.stack([p, p + [0.3, 0.0, 0.0]]), np.stack([r, r])))
        tops.append(scene.nail_top.copy())
    assert tops[0][0] < NAIL[2]  # the random path did hit the nail
    np.testing.assert_array_equal(tops[0], tops[1])


def rotation_about_y(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
