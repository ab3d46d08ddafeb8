"""Synthetic demonstrations have the described task properties, human timing and seeded noise."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.demos import DemoError, synthesize_demo, synthesize_motion
from toolimit.demos.synthetic import DEMONSTRATOR_SCYTHE_LENGTH
from toolimit.scenes import make_scene
from toolimit.scenes.scythe_cut import scythe_cut_rule
from toolimit.tools import ToolPose, tool_poses, tool_spec
from toolimit.tools.frame import swing_rotation

CASES = [(seed, 24) for seed in range(6)] + [(6, 30), (7, 30)]


def _rest_speed(demo, frames: slice) -> float:
    return float(np.max(demo.speed()[frames]))


@pytest.mark.parametrize("tool", ["spade", "hammer", "scythe"])
@pytest.mark.parametrize("seed, fps", CASES)
def test_common_properties(tool, seed, fps):
    motion = synthesize_motion(tool, seed, fps)
    clean, noisy = motion.clean, motion.noisy
    assert clean.tool == tool and clean.fps == fps
    assert 2.5 <= clean.duration <= 6.0
    # the demonstrator's tool: the simulated one, but a real scythe for the scythe (longer)
    length = DEMONSTRATOR_SCYTHE_LENGTH if tool == "scythe" else tool_spec(tool).length
    np.testing.assert_allclose(clean.lengths, length, atol=1e-9)
    assert _rest_speed(clean, slice(0, 3)) < 0.05 and _rest_speed(clean, slice(-3, None)) < 0.05
    assert clean.head[:, 2].min() > 0.0 and clean.handle[:, 2].min() > 0.0
    assert clean.speed().max() < 4.5
    # Noise: a few mm everywhere but the outliers, which are 2-6 % of frames and off by > 5 cm.
    error = np.maximum(
        np.linalg.norm(noisy.head - clean.head, axis=1), np.linalg.norm(noisy.handle - clean.handle, axis=1)
    )
    inliers = np.setdiff1d(np.arange(clean.n_frames), motion.outlier_frames)
    assert 0.002 <= motion.jitter <= 0.005
    assert np.median(error[inliers]) < 0.012 and error[inliers].max() < 0.03
    assert 1 <= motion.outlier_frames.size <= 0.07 * clean.n_frames
    assert np.all(error[motion.outlier_frames] > 0.05)


@pytest.mark.parametrize("seed, fps", CASES)
def test_spade_scoops_at_ground_level_carries_level_and_dumps(seed, fps):
    motion = synthesize_motion("spade", seed, fps)
    demo, events = motion.clean, motion.events
    entry, push_end = events["scoop"]
    scoop = demo.head[entry : push_end + 1]
    assert np.all((scoop[:, 2] >= 0.0) & (scoop[:, 2] <= 0.05))
    assert 0.15 <= np.linalg.norm(scoop[-1, :2] - scoop[0, :2]) <= 0.26
    start, end = events["carry"]
    carry = demo.head[start : end + 1]
    assert 0.4 <= np.linalg.norm(carry[-1, :2] - carry[0, :2]) <= 0.9
    assert np.ptp(carry[:, 2]) < 0.04 and 0.3 <= carry[:, 2].mean() <= 0.5
    _, dumped = events["dump"]
    assert 0.25 <= demo.head[dumped, 2] <= 0.5
    assert np.linalg.norm(demo.head[dumped, :2] - demo.head[end, :2]) < 0.08  # poured where carried
    # The blade turns to pour: the tool axis steepens from under 30 to over 65 degrees.
    elevation = np.degrees(np.arcsin(demo.axis[:, 2]))
    assert elevation[end] < 30 and elevation[dumped] > 65


@pytest.mark.parametrize("seed, fps", CASES)
def test_hammer_strikes_the_same_height_fast_and_face_down(seed, fps):
    motion = synthesize_motion("hammer", seed, fps)
    demo, impacts = motion.clean, motion.events["impacts"]
    nail = motion.params["nail_height"]
    assert 2 <= len(impacts) <= 4
    np.testing.assert_allclose(demo.head[impacts, 2], nail, atol=1e-9)
    assert demo.head[:, 2].min() >= nail - 1e-9
    for impact, previous in zip(impacts, [0] + impacts[:-1]):
        velocity = (demo.head[impact] - demo.head[impact - 1]) * fps  # what a video would show
        assert 2.0 <= np.linalg.norm(velocity) <= 4.0
        across = velocity - np.dot(velocity, demo.axis[impact]) * demo.axis[impact]
        assert across[2] / np.linalg.norm(across) < -0.9  # the striking face moves down
        assert abs(demo.axis[impact, 2]) < np.sin(np.radians(15))  # handle nearly level at impact
        assert 0.2 <= demo.head[previous:impact, 2].max() - nail <= 0.35
        rebound = demo.head[impact + 1 : impact + 6, 2] - nail
        assert 0.0 < rebound.max() < 0.07


@pytest.mark.parametrize("seed, fps", CASES)
def test_scythe_draws_the_blade_low_towards_the_hands_with_the_snath_nearly_level(seed, fps):
    """What the authors' cut rule needs (toolimit.scenes.scythe_cut): the snath within 30 degrees of
    horizontal and the edge moving towards the hands at more than 1 m/s, at most 0.1 m high."""
    motion = synthesize_motion("scythe", seed, fps)
    demo, draws = motion.clean, motion.events["sweeps"]
    assert 1 <= len(draws) <= 2
    velocity = demo.head_velocity()
    for start, end in draws:
        frames = slice(start, end + 1)
        assert end - start >= 3  # at least three frames of the draw at the video's rate
        assert np.all((demo.head[frames, 2] >= 0.02) & (demo.head[frames, 2] <= 0.05))
        elevation = np.degrees(np.arcsin(demo.axis[frames, 2]))
        assert np.all((elevation >= 5 - 1e-9) & (elevation <= 20 + 1e-9))
        snath = demo.axis[frames, :2] / np.linalg.norm(demo.axis[frames, :2], axis=1, keepdims=True)
        towards_hands = np.sum(velocity[frames, :2] * snath, axis=1)  # the head's speed along the snath
        assert np.all((towards_hands >= 1.5) & (towards_hands <= 2.3))
        across = np.linalg.norm(velocity[frames, :2] - towards_hands[:, None] * snath, axis=1)
        assert np.all((across >= 0.3) & (across <= 0.95))  # the body turns: the blade slides along its length
        turn = snath[0, 0] * snath[-1, 1] - snath[0, 1] * snath[-1, 0]  # z of their cross product
        assert turn > 0  # right to left: the snath turns counter-clockwise
    # The head moves towards the hands fastest in the draw: the half second of swing before it and
    # of follow-through after it ramp that speed up and down.
    snath = demo.axis[:, :2] / np.linalg.norm(demo.axis[:, :2], axis=1, keepdims=True)
    towards_hands = np.sum(velocity[:, :2] * snath, axis=1)
    half_second = int(fps / 2)
    for start, end in draws:
        around = np.r_[max(start - half_second, 0) : start, end + 1 : end + 1 + half_second]
        assert towards_hands[around].max() < towards_hands[start : end + 1].min()
    if len(draws) > 1:  # the mower steps forward between strokes
        first, last = demo.head[draws[0][0]], demo.head[draws[-1][0]]
        assert 0.05 <= np.linalg.norm(last[:2] - first[:2]) <= 0.7


@pytest.mark.parametrize("seed", range(6))
def test_a_scythe_draw_over_the_patch_cuts_every_stalk_by_the_authors_rule(seed):
    """With the blade level, its tip leading, and the authors' patch (10 stalks in 0.4 x 0.1 m)
    centred under the edge half-way through the first draw, the demonstrated motion cuts the
    stalks, and they fall around the draw (from 3 control steps before it to 2 after it)."""
    motion = synthesize_motion("scythe", seed, fps=24)  # the scene's control rate
    demo = motion.clean
    start, end = motion.events["sweeps"][0]
    middle = (start + end) // 2
    blade = np.cross([0.0, 0.0, 1.0], demo.axis[middle])
    blade *= np.sign(blade @ demo.head_velocity()[middle]) / np.linalg.norm(blade)
    swing = swing_rotation(demo.axis[middle])
    poses = tool_poses(demo.head, demo.handle, np.arctan2(blade @ swing[:, 1], blade @ swing[:, 0]))
    edge_centre = poses.position[middle] + poses.rotation[middle] @ scythe_cut_rule(0.005).edge.mean(axis=0)
    scene, instances = make_scene("scythe", "3d"), 8
    scene.reset({"grass_position": np.array([*edge_centre[:2], 0.0])}, np.random.default_rng(seed), instances)
    for position, rotation in zip(poses.position, poses.rotation):
        scene.step(ToolPose(np.repeat(position[None], instances, 0), np.repeat(rotation[None], instances, 0)))
    assert scene.goal_reward().mean() >= 9.5
    steps = scene.cut_time[np.isfinite(scene.cut_time)] / scene.control_dt  # since the first pose
    assert steps.min() >= start - 3 and steps.max() <= end + 2


def test_determinism_and_variety():
    for tool in ("spade", "hammer", "scythe"):
        a, b = synthesize_demo(tool, 3), synthesize_demo(tool, 3)
        np.testing.assert_array_equal(a.head, b.head)
        np.testing.assert_array_equal(a.handle, b.handle)
        c = synthesize_demo(tool, 4)
        assert a.n_frames != c.n_frames or not np.allclose(a.head, c.head)
        clean = synthesize_demo(tool, 3, noise=False)
        np.testing.assert_array_equal(clean.head, synthesize_motion(tool, 3).clean.head)
        assert not np.allclose(clean.head, a.head)


def test_bad_arguments():
    with pytest.raises(DemoError, match="no synthetic demonstrations for 'rake'"):
        synthesize_demo("rake", 0)
    with pytest.raises(DemoError, match="fps: must be between 1 and 1000"):
        synthesize_demo("spade", 0, fps=0)
