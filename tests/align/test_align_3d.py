"""Alignment in the 3D spade world, end to end on a tiny budget (real particle physics, no fakes).

Only one 3D spade sample in a few hundred earns a reward (benchmarks/alignment_3d.py: the first
candidate of the shipped spade demos comes after 99 to 812 samples from seed 0), and each replay
simulates 200 sand spheres at 240 Hz, too much for a unit test's budget on a shared machine. The
search's outcome depends only on (seed, sample index), so the test uses a seed whose first
sample is a candidate: SEED was found by scanning seeds from 0 with CONFIG on
data/demos/spade_00.npz (re-picked when the spade world became the authors' scene, issue 9). If the sampler or the spade world changes, that sample may stop scoring
and the tests fail: re-pick SEED by scanning seeds with CONFIG.
"""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.align.config import AlignmentConfig
from toolimit.align.sampler import draw_alignment_sample
from toolimit.align.search import AlignmentResult, align
from toolimit.demos import clean_demo, load_demo
from toolimit.scenes.registry import make_scene
from toolimit.scenes.spatial.spade import GOAL_INNER, GOAL_REGION_HEIGHT
from toolimit.viz.meshcat_views import replay_scene

SEED = 0
# chunk_size 1: with two workers the three samples are spread over both processes.
CONFIG = AlignmentConfig(samples=3, candidates=1, replays=3, chunk_size=1)


@pytest.fixture(scope="module")
def spade_demo(repo_root):
    demo, _ = clean_demo(load_demo(repo_root / "data" / "demos" / "spade_00.npz"))
    return demo


@pytest.fixture(scope="module")
def one_worker(spade_demo) -> AlignmentResult:
    return align(spade_demo, "spade", "3d", CONFIG, seed=SEED, workers=1, progress=False, clean=False)


def summary(result: AlignmentResult) -> tuple:
    return (
        [(c.index, c.replay_rewards.tolist(), c.sample.to_dict()) for c in result.candidates],
        result.samples_tried,
        result.samples_rejected,
        result.rejection_reasons,
    )


def test_tiny_3d_search_finds_a_candidate_with_sand_in_the_goal_box(one_worker):
    result = one_worker
    assert result.world == "3d" and result.plane is None  # the demo is not flattened in 3D
    assert len(result.candidates) == 1, f"no candidate in {result.samples_tried} samples: {result.rejection_reasons}"
    candidate = result.best
    assert candidate.reward > 0.0
    assert candidate.replay_rewards.shape == (CONFIG.replays,)
    assert np.all(candidate.replay_rewards == np.round(candidate.replay_rewards))  # whole spheres
    assert result.samples_to_first_candidate == candidate.index + 1 <= CONFIG.samples

    # Replay the candidate as the search's screening run did (same generator, one instance) and
    # count the sphere centres inside the goal box from the scene's raw state, not its reward.
    scene = make_scene("spade", "3d")
    rng = np.random.default_rng([SEED, candidate.index])
    redrawn = draw_alignment_sample(
        result.demo, result.keypoints, scene.parameters, CONFIG, CONFIG.element_covariance(None),
        result.min_distance, rng,
    )
    assert redrawn.to_dict() == candidate.sample.to_dict()
    _, _, poses = result.aligned_motion(candidate)
    final = replay_scene(scene, poses, candidate.sample.params, rng)[-1]
    offset = final["sphere_positions"] - np.asarray(candidate.sample.params["goal_position"]) * [1.0, 1.0, 0.0]
    inside = (np.abs(offset[:, :2]) < GOAL_INNER / 2).all(axis=1) & (offset[:, 2] >= 0) & (offset[:, 2] <= GOAL_REGION_HEIGHT)
    assert inside.sum() > 0
    assert inside.sum() == final["in_box"]


def test_same_3d_result_with_two_workers(spade_demo):
    # Eight samples, one per chunk, so that both workers replay some; the search may stop earlier
    # at its second candidate: then both runs must stop there.
    config = AlignmentConfig(samples=8, candidates=2, replays=3, chunk_size=1)
    one = align(spade_demo, "spade", "3d", config, seed=SEED, workers=1, progress=False, clean=False)
    two = align(spade_demo, "spade", "3d", config, seed=SEED, workers=2, progress=False, clean=False)
    assert one.candidates, "seed SEED should give a candidate within 3 samples (see the module docstring)"
    assert summary(two) == summary(one)
