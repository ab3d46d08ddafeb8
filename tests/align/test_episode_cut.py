"""The authors' episode cut for timed goals: the frames it keeps, where alignment finds it, what
its files record, and the learning task's horizon."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.align.config import AlignmentConfig
from toolimit.align.episode_cut import AFTER_REWARD_FRAMES, KEPT_FRAMES, EpisodeCut, first_reward_cut, is_timed
from toolimit.align.outputs import write_alignment
from toolimit.align.search import align
from toolimit.demos import load_demo
from toolimit.learn.task import success_horizon
from toolimit.robots import make_robot
from toolimit.scenes.registry import make_scene
from toolimit.scenes.replay import replay, speed_limited
from toolimit.tools import tool_spec
from toolimit.trajopt.selection import load_candidates


def test_the_cut_keeps_the_last_20_poses_of_the_motion_to_5_frames_after_the_first_reward():
    late = EpisodeCut(first_reward_frame=30)
    assert (late.start, late.frames) == (30 + 1 + AFTER_REWARD_FRAMES - KEPT_FRAMES, KEPT_FRAMES) == (16, 20)
    np.testing.assert_array_equal(late.apply(np.arange(40)), range(16, 36))  # the motion carries on
    # a motion that ends within the 5 frames after the reward: its last pose is held
    np.testing.assert_array_equal(late.apply(np.arange(33)), [*range(16, 33), 32, 32, 32])
    early = EpisodeCut(first_reward_frame=5)  # a shorter motion keeps all of it
    assert (early.start, early.frames) == (0, 11)
    assert early.apply(np.zeros((40, 3, 3))).shape == (11, 3, 3)
    assert late.record() == {
        "first_reward_frame": 30,
        "episode_start_frame": 16,
        "episode_frames": 20,
        "frames_after_reward": 5,
    }


def test_the_first_rewarded_replay_decides_the_cut():
    rewards = np.zeros((12, 3))  # (steps, replays)
    assert first_reward_cut(rewards) is None
    rewards[9:, 2] = 1.0  # replay 2 earns at step 9
    rewards[7:, 1] = 1.0  # replay 1 earns at step 7
    assert first_reward_cut(rewards) == EpisodeCut(7)
    rewards[10:, 0] = 1.0  # replay 0 comes first in order, though later in time
    assert first_reward_cut(rewards) == EpisodeCut(10)


def test_only_the_timed_scenes_are_cut():
    timed = {
        (tool, world): is_timed(make_scene(tool, world))
        for tool in ("spade", "hammer", "scythe")
        for world in ("planar", "3d")
    }
    assert timed == {(t, w): t != "spade" for t, w in timed}


@pytest.fixture(scope="module")
def hammer_alignment(repo_root, tmp_path_factory):
    config = AlignmentConfig(samples=40, candidates=2)
    result = align(load_demo(repo_root / "data" / "demos" / "hammer_00.npz"), "hammer", "3d", config, progress=False)
    out = tmp_path_factory.mktemp("hammer_alignment")
    write_alignment(result, out, "hammer_00")
    return result, out


def test_alignment_cuts_a_hammer_candidate_at_its_first_planted_nail(hammer_alignment):
    result, _ = hammer_alignment
    assert len(result.candidates) == 2
    for candidate in result.candidates:
        cut = candidate.cut
        assert cut is not None and cut.first_reward_frame >= KEPT_FRAMES  # hammer_00's first strike is after 1 s
        # the motion as the speed-limited tool reached it in the replays
        full = speed_limited(
            result.aligned_motion(candidate)[2], 1 / result.demo.fps, tool_spec("hammer").steered_offset
        )
        episode = result.episode_poses(candidate)
        assert len(episode.position) == KEPT_FRAMES
        np.testing.assert_array_equal(
            episode.position, full.position[cut.start : cut.first_reward_frame + 1 + AFTER_REWARD_FRAMES]
        )
        # the full motion earns nothing before the cut's last moving step, and the episode earns the goal in time
        scene = make_scene("hammer", "3d")
        before = replay(
            scene,
            candidate.sample.params,
            np.random.default_rng(0),
            type(full)(full.position[: cut.start], full.rotation[: cut.start]),
        )
        assert before[0] == 0.0
        rewards = replay(scene, candidate.sample.params, np.random.default_rng(0), episode, batch_size=4)
        assert np.all(rewards > 0.0) and scene.is_success().all()


def test_the_alignment_files_record_the_cut_and_hand_on_the_episode(hammer_alignment):
    result, out = hammer_alignment
    tool, world, candidates = load_candidates(out)
    assert (tool, world) == ("hammer", "3d")
    for loaded, candidate in zip(candidates, result.candidates):
        np.testing.assert_allclose(loaded.targets.positions, result.episode_poses(candidate).position)
    arrays = np.load(out / "candidates.npz")
    np.testing.assert_array_equal(arrays["first_reward_frame"], [c.cut.first_reward_frame for c in result.candidates])
    np.testing.assert_array_equal(arrays["episode_frames"], [KEPT_FRAMES] * 2)
    demo = np.load(out / "aligned_demo.npz")
    assert len(demo["tip_position"]) == len(demo["head"]) == len(demo["roll"]) == KEPT_FRAMES


def test_the_horizon_of_a_timed_goal_is_the_trajectory():
    """Holding still cannot plant the nail within the window later: H = T (the authors')."""
    robot = make_robot("planar3", tool="hammer")
    reference = np.repeat(robot.q_neutral[None], 8, axis=0)
    scene = make_scene("hammer", "planar")
    params = {"nail_position": np.array([2.0, 0.0, scene.protrusion])}  # out of reach: never a success
    assert success_horizon(robot, scene, params, np.zeros(3), reference, np.random.default_rng(0)) == 7
