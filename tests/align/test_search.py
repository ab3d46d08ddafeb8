"""The search's mechanics on a tiny fake scene: candidates, counts, rejection, determinism."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from align_fake_scene import FakeTargetScene, make_demo

from toolimit.align.config import AlignmentConfig
from toolimit.align.sampler import apply_alignment_sample, draw_alignment_sample
from toolimit.align.search import Candidate, Unaccepted, align

# ground_tolerance 10 m: no sample is rejected for going below the ground unless a test asks.
CONFIG = AlignmentConfig(samples=400, candidates=4, replays=5, chunk_size=16, element_std=0.05, ground_tolerance=10.0)


def run(workers: int = 1, config: AlignmentConfig = CONFIG, seed: int = 3, checkpoint=None, factory=None, **scene_kwargs):
    factory = factory or functools.partial(FakeTargetScene, **scene_kwargs)
    return align(
        make_demo(), "spade", "planar", config, seed=seed, workers=workers, progress=False, scene_factory=factory,
        checkpoint=checkpoint,
    )


def summary(result):
    return (
        [(c.index, c.reward, c.replay_rewards.tolist(), c.sample.to_dict()) for c in result.candidates],
        result.samples_tried,
        result.samples_rejected,
        result.samples_to_first_candidate,
        result.rejection_reasons,
    )


def test_first_k_candidates_in_index_order_with_their_counts():
    result = run()
    assert len(result.candidates) == CONFIG.candidates
    indices = [c.index for c in result.candidates]
    assert indices == sorted(indices)
    assert result.samples_tried == indices[-1] + 1
    assert result.samples_to_first_candidate == indices[0] + 1
    assert all(c.reward > 0 and c.replay_rewards.shape == (CONFIG.replays,) for c in result.candidates)
    assert np.isclose(result.best.reward, max(c.reward for c in result.candidates))
    assert result.wall_time_s > 0 and result.samples_rejected == 0
    # The demo was projected to the x-z plane and kept at the scene's 24 fps.
    assert np.all(result.demo.head[:, 1] == 0.0) and result.demo.fps == 24.0


def test_candidates_really_reach_the_target():
    result = run()
    for candidate in result.candidates:
        _, _, poses = result.aligned_motion(candidate)
        distance = np.linalg.norm(poses.position - candidate.sample.params["target"], axis=1).min()
        assert distance < 1.2 * candidate.sample.params["radius"]


def test_same_result_whatever_the_number_of_workers():
    config = AlignmentConfig(samples=300, candidates=6, replays=3, chunk_size=8, element_std=0.05)
    one = run(workers=1, config=config, reject_below_x=0.25)
    two = run(workers=2, config=config, reject_below_x=0.25)
    assert summary(one) == summary(two)
    assert one.samples_rejected > 0 and len(one.candidates) == 6


def test_rejections_are_counted_exactly():
    config = AlignmentConfig(samples=120, candidates=1000, replays=2, chunk_size=32, element_std=0.05, ground_tolerance=10.0)
    result = run(config=config, reject_below_x=0.3)
    scene = FakeTargetScene()
    expected = 0
    for index in range(config.samples):
        sample = draw_alignment_sample(
            result.demo, result.keypoints, scene.parameters, config, config.element_covariance("xz"),
            result.min_distance, np.random.default_rng([3, index]),
        )
        expected += sample.params["target"][0] < 0.3
    assert result.samples_tried == config.samples  # fewer candidates than asked: all samples tried
    assert result.samples_rejected == expected > 0
    assert result.rejection_reasons == {"target: x # below #": expected}


def test_samples_taking_the_tool_below_the_ground_are_rejected():
    config = AlignmentConfig(samples=150, candidates=1000, replays=2, z_offset_std=0.3, ground_tolerance=0.02)
    result = run(config=config)
    scene = FakeTargetScene()
    expected = 0
    for index in range(config.samples):
        sample = draw_alignment_sample(
            result.demo, result.keypoints, scene.parameters, config, config.element_covariance("xz"),
            result.min_distance, np.random.default_rng([3, index]),
        )
        aligned, _, _ = apply_alignment_sample(result.demo, result.keypoints, sample)
        expected += aligned.head[:, 2].min() < -0.02
    assert result.samples_rejected == expected > 10
    assert result.rejection_reasons == {"sampler: the tool head goes # m below the ground": expected}
    for candidate in result.candidates:
        _, _, poses = result.aligned_motion(candidate)
        assert poses.position[:, 2].min() >= -0.02


def test_no_candidate_when_nothing_earns_a_reward():
    config = AlignmentConfig(samples=40, candidates=2, replays=2, chunk_size=16)
    result = run(config=config, radius_high=1e-9)
    assert result.candidates == [] and result.best is None
    assert result.samples_tried == 40 and result.samples_to_first_candidate is None


def test_demo_is_resampled_to_the_control_rate_and_config_is_checked():
    demo = make_demo(n_frames=76, fps=30.0)  # 2.5 s
    result = align(demo, "spade", "planar", CONFIG, seed=0, progress=False, scene_factory=FakeTargetScene)
    assert result.demo.fps == 24.0 and result.demo.n_frames == 61
    with pytest.raises(ValueError, match="samples"):
        AlignmentConfig(samples=0)
    with pytest.raises(ValueError, match="workers"):
        align(demo, "spade", "planar", CONFIG, workers=0, scene_factory=FakeTargetScene)


def test_screening_replays_only_rewarded_samples_in_full():
    from toolimit.align.search import SampleEvaluator

    demo = make_demo()
    result = run()
    # Screening: a zero-reward sample ran once (or all runs, if its one run had a reward).
    for screen, runs_of_zero_reward in ((1, {1, CONFIG.replays}), (0, {CONFIG.replays})):
        config = AlignmentConfig(replays=CONFIG.replays, screen_replays=screen, element_std=0.05, ground_tolerance=10.0)
        evaluator = SampleEvaluator(
            FakeTargetScene(), result.demo, result.keypoints, config, "xz", result.min_distance, 3
        )
        outcomes = [evaluator.evaluate(i) for i in range(60)]
        zero = [o for o in outcomes if o.reward == 0.0]
        rewarded = [o for o in outcomes if isinstance(o, Candidate)]
        assert zero and rewarded and demo.n_frames == result.demo.n_frames
        assert {len(o.replay_rewards) for o in zero} <= runs_of_zero_reward
        assert min(len(o.replay_rewards) for o in zero) == min(runs_of_zero_reward)
        assert all(len(o.replay_rewards) == CONFIG.replays and o.sample is not None for o in rewarded)


def test_a_crashed_search_resumes_from_its_checkpoint_with_the_same_result(tmp_path, monkeypatch):
    from align_fake_scene import CrashingScene

    import toolimit.align.search as search

    monkeypatch.setattr(search, "CHECKPOINT_EVERY_S", 0.0)  # save after every chunk
    config = AlignmentConfig(samples=300, candidates=5, replays=3, chunk_size=10, element_std=0.05, ground_tolerance=10.0)
    checkpoint = tmp_path / "search.json"
    uninterrupted = run(config=config)
    with pytest.raises(RuntimeError, match="simulated crash"):
        run(config=config, checkpoint=checkpoint, factory=functools.partial(CrashingScene, 12))
    saved = json.loads(checkpoint.read_text())
    assert 0 < saved["samples_tried"] < uninterrupted.samples_tried and saved["candidates"]
    resumed = run(config=config, checkpoint=checkpoint)
    assert summary(resumed) == summary(uninterrupted)
    assert not checkpoint.exists()  # removed once the search ends
    # A checkpoint made under other settings is ignored (fresh search, same result).
    checkpoint.write_text(json.dumps({**saved, "key": {**saved["key"], "seed": 99}}))
    assert summary(run(config=config, checkpoint=checkpoint)) == summary(uninterrupted)


def test_demo_preparation_uses_the_worlds_plane():
    from toolimit.align.search import prepare_demo

    demo = make_demo()
    tilted = demo.rotated_yaw(0.7)  # motion no longer along x
    flat, plane = prepare_demo(tilted, "hammer", "planar", 1 / 24)
    assert plane == "xz" and np.all(flat.head[:, 1] == 0.0)
    np.testing.assert_allclose(np.ptp(flat.head[:, 0]), np.ptp(demo.head[:, 0]), rtol=1e-6)
    same, plane = prepare_demo(tilted, "scythe", "planar", 1 / 24)
    assert plane == "xy" and np.array_equal(same.head, tilted.head)
    spatial, plane = prepare_demo(tilted, "spade", "3d", 1 / 24)
    assert plane is None and np.array_equal(spatial.head, tilted.head)


def test_align_cleans_the_demo_by_default_like_the_cli():
    from toolimit.demos import ToolDemo, clean_demo

    smooth = make_demo()
    jump = np.zeros_like(smooth.head)
    jump[20, 2] = 0.3  # an outlier frame, as a reconstruction gives
    noisy = ToolDemo(smooth.head + jump, smooth.handle + jump, smooth.fps, "spade")
    config = AlignmentConfig(samples=16, candidates=1, replays=2, chunk_size=16, ground_tolerance=10.0)
    default = align(noisy, "spade", "planar", config, progress=False, scene_factory=FakeTargetScene)
    assert default.cleaning is not None and 20 in default.cleaning.replaced_frames.tolist()
    cleaned, _ = clean_demo(noisy)
    by_hand = align(cleaned, "spade", "planar", config, progress=False, scene_factory=FakeTargetScene, clean=False)
    assert by_hand.cleaning is None
    np.testing.assert_array_equal(default.demo.head, by_hand.demo.head)
    np.testing.assert_array_equal(default.keypoints, by_hand.keypoints)
    raw = align(noisy, "spade", "planar", config, progress=False, scene_factory=FakeTargetScene, clean=False)
    assert not np.array_equal(raw.demo.head, default.demo.head)


def test_pose_targets_from_an_alignment_are_what_trajopt_reads(tmp_path):
    from toolimit.align.outputs import write_alignment
    from toolimit.trajopt import load_pose_targets, targets_from_alignment

    result = run()
    write_alignment(result, tmp_path, "demo.npz")
    from_file = load_pose_targets(tmp_path / "aligned_demo.npz")
    targets = targets_from_alignment(result)
    np.testing.assert_allclose(targets.positions, from_file.positions, atol=1e-12)
    np.testing.assert_allclose(targets.rotations, from_file.rotations, atol=1e-9)
    assert targets.fps == from_file.fps
    second = targets_from_alignment(result, result.candidates[1])
    assert not np.allclose(second.positions, targets.positions) or result.best is result.candidates[1]


class RewardedInK(FakeTargetScene):
    """Every run of one instance earns a reward; of a larger batch, exactly the first ``k`` instances."""

    def __init__(self, k: int) -> None:
        super().__init__()
        self.k = k

    def goal_reward(self) -> np.ndarray:
        return (np.arange(self.batch_size) < (1 if self.batch_size == 1 else self.k)).astype(float)


@pytest.mark.parametrize("k, accepted", [(0, False), (1, False), (2, True), (10, True)])
def test_a_candidate_needs_a_reward_in_two_of_ten_replays(k, accepted):
    """The authors' rule (``acceptable_success_n = 2`` of ``double_check_n = 10``)."""
    from toolimit.align.search import SampleEvaluator

    result = run()
    config = AlignmentConfig(element_std=0.05, ground_tolerance=10.0)
    assert (config.replays, config.accept_replays, config.screen_replays) == (10, 2, 1)
    evaluator = SampleEvaluator(RewardedInK(k), result.demo, result.keypoints, config, "xz", result.min_distance, 3)
    outcome = evaluator.evaluate(0)
    assert isinstance(outcome, Candidate if accepted else Unaccepted)
    assert np.count_nonzero(outcome.replay_rewards) == k and len(outcome.replay_rewards) == 10


@pytest.mark.parametrize("accept", [0, 6])
def test_accept_replays_must_lie_between_one_and_replays(accept):
    with pytest.raises(ValueError, match="accept_replays"):
        AlignmentConfig(replays=5, accept_replays=accept)
