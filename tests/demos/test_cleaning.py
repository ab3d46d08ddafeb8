"""Cleaning: injected outliers are found and replaced, real flips removed, clean demos kept."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.demos import DemoError, ToolDemo, clean_demo, load_demo, synthesize_motion
from toolimit.demos.cleaning import step_axis_rates, step_speeds


def _rms(a, b) -> float:
    return float(np.sqrt(np.mean(np.sum((a.head - b.head) ** 2, 1) + np.sum((a.handle - b.handle) ** 2, 1)) / 2))


@pytest.mark.parametrize("tool", ["spade", "hammer", "scythe"])
def test_injected_outliers_are_found_and_the_error_drops(tool):
    found = missed = false = 0
    for seed in range(12):
        motion = synthesize_motion(tool, seed, fps=24 if seed % 4 else 30)
        cleaned, report = clean_demo(motion.noisy)
        truth, flagged = set(motion.outlier_frames.tolist()), set(report.replaced_frames.tolist())
        found, missed, false = found + len(truth & flagged), missed + len(truth - flagged), false + len(flagged - truth)
        before, after = _rms(motion.noisy, motion.clean), _rms(cleaned, motion.clean)
        assert after < 0.012 and after < 0.4 * before, (seed, before, after)
        np.testing.assert_allclose(cleaned.lengths, cleaned.length, atol=1e-9)
    assert found / (found + missed) >= 0.95  # recall
    assert found / (found + false) >= 0.85  # precision


@pytest.mark.parametrize("tool", ["spade", "hammer", "scythe"])
def test_a_clean_demo_comes_out_nearly_unchanged(tool):
    for seed in range(4):
        clean = synthesize_motion(tool, seed).clean
        cleaned, report = clean_demo(clean)
        assert report.n_replaced == 0
        change = np.maximum(
            np.linalg.norm(cleaned.head - clean.head, axis=1), np.linalg.norm(cleaned.handle - clean.handle, axis=1)
        )
        assert change.max() < 0.009 and _rms(cleaned, clean) < 0.003


def test_smoothing_can_be_switched_off():
    clean = synthesize_motion("hammer", 0).clean
    cleaned, _ = clean_demo(clean, smooth=False)
    np.testing.assert_allclose(cleaned.head, clean.head, atol=1e-12)
    np.testing.assert_allclose(cleaned.handle, clean.handle, atol=1e-12)


def test_real_spade_flips_are_removed(video_demos_dir):
    demo = load_demo(video_demos_dir / "spade_video1_aligned.npz")
    assert step_axis_rates(demo).max() > 15 and step_speeds(demo).max() > 7  # the known flips
    cleaned, report = clean_demo(demo)
    # The stretches between the flips (rows 19/20 ... 35/36 and 82/83 ... 90/91) are replaced.
    assert set(range(20, 36)) | set(range(83, 91)) <= set(report.replaced_frames.tolist())
    assert report.n_replaced <= 30
    max_axis_rate, max_speed = report.thresholds["max_axis_rate"], report.thresholds["max_speed"]
    assert step_axis_rates(cleaned).max() <= max_axis_rate / 2
    assert step_speeds(cleaned).max() <= max_speed / 2
    assert report.max_axis_rate_after == pytest.approx(step_axis_rates(cleaned).max())
    # Where the video was fine, the motion is kept within a centimetre.
    kept = np.setdiff1d(np.arange(demo.n_frames), report.replaced_frames)
    assert np.linalg.norm(cleaned.head[kept] - demo.head[kept], axis=1).max() < 0.011
    # The flips turn the tool about its blade: the blade's path (its thrust into the sand at frames
    # 19-24, the dig) is kept through them, only the axis is replaced.
    assert report.head_replaced_frames.size == 0
    assert np.linalg.norm(cleaned.head - demo.head, axis=1).max() <= report.thresholds["max_smoothing_shift"] + 1e-9


def test_a_flip_about_the_head_keeps_the_head_path():
    clean = synthesize_motion("spade", 0).clean
    handle = clean.handle.copy()
    handle[30:41] = 2 * clean.head[30:41] - handle[30:41]  # the axis reversed, the head where it was
    cleaned, report = clean_demo(ToolDemo(clean.head, handle, clean.fps, "spade"))
    assert report.replaced_frames.tolist() == list(range(30, 41)) and report.head_replaced_frames.size == 0
    assert np.linalg.norm(cleaned.head - clean.head, axis=1).max() < 0.006
    assert np.degrees(np.arccos(np.clip(np.sum(cleaned.axis * clean.axis, axis=1), -1, 1))).max() < 2.0


def test_real_spade_example_without_flips_is_kept(video_demos_dir):
    demo = load_demo(video_demos_dir / "spade_example_aligned.npz")
    cleaned, report = clean_demo(demo)
    assert report.n_replaced == 0
    assert np.linalg.norm(cleaned.head - demo.head, axis=1).max() < 0.011


def test_hopeless_demo_is_an_error():
    clean = synthesize_motion("spade", 0).clean
    rng = np.random.default_rng(0)
    jumps = rng.normal(0.0, 0.3, clean.head.shape) * (rng.random((clean.n_frames, 1)) < 0.7)
    broken = ToolDemo(clean.head + jumps, clean.handle + jumps, clean.fps, "spade")  # 70 % of frames thrown about
    with pytest.raises(DemoError, match="too broken to clean"):
        clean_demo(broken)
