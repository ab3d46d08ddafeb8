"""The scripted motions (the LfD baseline's demonstrations) solve their scenes with the tool alone."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.errors import NoScriptedMotion
from toolimit.scenes.registry import make_scene, scripted_motion
from toolimit.scenes.replay import replay
from toolimit.tools import hold_last

CASES = [  # tool, world, scene parameters, the goal reward every instance must reach
    ("spade", "planar", {"sand_position": np.array([0.84, 0.0, 0.0]), "goal_position": np.array([0.42, 0.0, 0.0])}, 10),
    (
        "spade",
        "3d",
        {"sand_position": np.array([0.2, -0.4, 0.0]), "sand_yaw": -1.5, "goal_position": np.array([0.85, -0.5, 0.0])},
        10,
    ),
    ("hammer", "3d", {"nail_position": np.array([0.29, -0.48, 0.15])}, 1),
    ("hammer", "3d", {"nail_position": np.array([0.0, 0.0, 0.6])}, 1),  # above the origin: handle along -x
    ("scythe", "3d", {"grass_position": np.array([0.27, 0.41, 0.0])}, 10),
]


@pytest.mark.parametrize(("tool", "world", "params", "goal"), CASES, ids=lambda case: str(case)[:20])
def test_the_scripted_motion_succeeds_with_the_tool_alone(tool, world, params, goal):
    """Replayed as given (the kinesthetic demonstration a robot tracks; the tool speed limit belongs to
    the alignment's replay), then held as long again (a learning task's horizon is at most twice its
    motion)."""
    scene = make_scene(tool, world)
    motion = scripted_motion(tool, world, params)
    assert motion.position.shape == (len(motion.rotation), 3) and motion.rotation.shape[1:] == (3, 3)
    np.testing.assert_allclose(
        motion.rotation @ np.swapaxes(motion.rotation, 1, 2),
        np.broadcast_to(np.eye(3), motion.rotation.shape),
        atol=1e-12,
    )
    held = hold_last(motion, len(motion.position))
    rewards = replay(scene, params, np.random.default_rng(0), held, batch_size=2, tool_alone=False)
    assert np.all(rewards >= goal), rewards
    assert np.all(scene.is_success())


def test_the_same_parameters_give_the_same_motion():
    params = CASES[1][2]
    first, second = scripted_motion("spade", "3d", params), scripted_motion("spade", "3d", params)
    np.testing.assert_array_equal(first.position, second.position)


def test_a_scene_without_a_scripted_motion_is_a_one_line_error():
    with pytest.raises(
        NoScriptedMotion, match=r"no scripted motion for the hammer in world 'planar'; scripted: .*spade/planar"
    ):
        scripted_motion("hammer", "planar", {})


@pytest.mark.parametrize(("tool", "world", "params", "goal"), CASES[:3] + CASES[4:], ids=lambda case: str(case)[:20])
def test_per_instance_positions_place_each_instance_where_its_own_motion_succeeds(tool, world, params, goal):
    """Instance 1's elements all stand 1 m further along x: the motion scripted for instance 0's
    positions succeeds there only, and the motion scripted for instance 1's there only."""
    shift = np.array([1.0, 0.0, 0.0])
    moved = {name: value + shift if np.ndim(value) == 1 else value for name, value in params.items()}
    per_instance = {name: np.stack([value, moved[name]]) if np.ndim(value) == 1 else value for name, value in params.items()}
    scene = make_scene(tool, world)
    for instance, own in enumerate((params, moved)):
        motion = hold_last(scripted_motion(tool, world, own), len(scripted_motion(tool, world, own).position))
        rewards = replay(scene, per_instance, np.random.default_rng(0), motion, batch_size=2, tool_alone=False)
        assert rewards[instance] >= goal and rewards[1 - instance] < goal, rewards
        assert scene.is_success().tolist() == [instance == 0, instance == 1]
