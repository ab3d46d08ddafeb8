"""Grader of exercise 01: velocity keypoints, checked against ``toolimit.align.keypoints``.

Each test draws demonstrations from a seeded generator, so a failure is reproducible: the message
names the seed, the frames you missed or added, and why they are (not) keypoints.
"""

from __future__ import annotations

import numpy as np
import pytest
from grading import case_seeds, check, fail, fmt, fmt_shape

from toolimit.align.keypoints import velocity_keypoints as reference_keypoints
from toolimit.demos import ToolDemo

MODULE = "ex01_velocity_keypoints"
SEEDS = case_seeds(8)
#: Existing implementations of this exercise: a submission calling one of them gets 0 (grading.py).
#: Points of each test group (all its cases share them): 10 for the exercise.
WEIGHTS = {
    "test_ex01_output_is_sorted_unique_int_frames": 1.5,
    "test_ex01_first_and_last_frame_are_keypoints": 2,
    "test_ex01_keypoints_match_reference": 6.5,
}
#: What each function returns, for the message on a value the checks cannot read.
RETURNS = {
    "velocity_keypoints": "a 1-D integer array of frame indices in 0..T-1, sorted, first and last frame included"
}
#: Imported in the student's process before their module (it may start no thread afterwards).
STUDENT_IMPORTS = ["numpy", "toolimit.demos", "toolimit.align"]
FORBIDDEN = ["toolimit.align.keypoints"]


def random_demo(seed: int) -> ToolDemo:
    """A smooth random tool motion (sum of sines plus a little noise), 20 to 300 frames."""
    rng = np.random.default_rng(seed)
    n_frames = int(rng.integers(20, 301))
    fps = float(rng.choice([24.0, 30.0]))
    t = np.arange(n_frames)[:, None] / fps
    frequencies = rng.uniform(0.2, 2.0, size=(3, 3))
    amplitudes = rng.uniform(0.05, 0.5, size=(3, 3))
    phases = rng.uniform(0, 2 * np.pi, size=(3, 3))
    head = sum(amplitudes[k] * np.sin(2 * np.pi * frequencies[k] * t + phases[k]) for k in range(3))
    head = head + rng.normal(scale=0.003, size=head.shape) + np.array([0.0, 0.0, 0.5])
    tilt = 0.5 * np.sin(2 * np.pi * rng.uniform(0.1, 1.0) * t[:, 0])
    axis = np.stack([np.sin(tilt), np.zeros_like(tilt), np.cos(tilt)], axis=1)
    return ToolDemo(head=head, handle=head + 0.4 * axis, fps=fps, tool="spade", source=f"grader seed {seed}")


def frame_indices(got, where: str) -> np.ndarray:
    """The student's answer as a 1-D integer array, or a failure naming what was expected."""
    try:
        frames = np.asarray(got, dtype=float).ravel()
    except (TypeError, ValueError):
        fail(f"{where}: expected a 1-D integer array of frame indices, got {fmt(got)}")
    check(
        np.all(np.isfinite(frames)) and np.all(frames == np.round(frames)),
        lambda: f"{where}: expected integer frame indices, got {fmt(frames)}",
    )
    return frames.astype(int)


def describe_frames(frames: np.ndarray, speed: np.ndarray, fraction: float) -> str:
    """One line per frame (the first four): its speed and whether it is a local maximum / minimum."""
    top, bottom = np.quantile(speed, 1 - fraction), np.quantile(speed, fraction)
    lines = []
    for t in frames[:4]:
        if not 0 <= t < len(speed):
            kind = f"outside the demonstration's frames 0..{len(speed) - 1}"
            lines.append(f"  frame {t}: {kind}")
            continue
        if t in (0, len(speed) - 1):
            kind = "an end frame"
        elif speed[t] > speed[t - 1] and speed[t] > speed[t + 1]:
            kind = f"a local maximum (top threshold {top:.4f} m/s)"
        elif speed[t] < speed[t - 1] and speed[t] < speed[t + 1]:
            kind = f"a local minimum (bottom threshold {bottom:.4f} m/s)"
        else:
            kind = "not a local extremum"
        lines.append(f"  frame {t}: speed {speed[t]:.4f} m/s, {kind}")
    if len(frames) > 4:
        lines.append(f"  and {len(frames) - 4} more")
    return "\n".join(lines)


@pytest.mark.parametrize("seed", SEEDS)
def test_ex01_output_is_sorted_unique_int_frames(submission, seed):
    demo = random_demo(seed)
    got = submission(MODULE).velocity_keypoints(demo, 0.05)
    frames = np.asarray(got)
    where = f"seed {seed}, fraction 0.05, {demo.n_frames} frames"
    check(frames.ndim == 1, f"{where}: expected a 1-D array of frame indices, got shape {fmt_shape(got)}")
    check(frames.size > 0, f"{where}: expected at least the first and the last frame, got an empty array")
    check(
        np.issubdtype(frames.dtype, np.integer),
        f"{where}: expected integer frame indices, got {frames.dtype} values {fmt(frames)}",
    )
    check(np.all(np.diff(frames) > 0), f"{where}: frames must be increasing and unique, got {fmt(frames, limit=20)}")
    check(
        frames.min() >= 0 and frames.max() < demo.n_frames,
        f"{where}: frames must lie in 0..{demo.n_frames - 1}, got {fmt(frames, limit=20)}",
    )


@pytest.mark.parametrize("seed", SEEDS)
def test_ex01_first_and_last_frame_are_keypoints(submission, seed):
    demo = random_demo(seed)
    frames = frame_indices(submission(MODULE).velocity_keypoints(demo, 0.05), f"seed {seed}")
    check(0 in frames, f"seed {seed}: the first frame (0) is always a keypoint; you returned {fmt(frames, limit=20)}")
    last = demo.n_frames - 1
    check(
        last in frames,
        f"seed {seed}, {demo.n_frames} frames: the last frame ({last}) is always a keypoint; "
        f"you returned {fmt(frames, limit=20)}",
    )


@pytest.mark.parametrize("fraction", [0.05, 0.1, 0.3])
@pytest.mark.parametrize("seed", SEEDS)
def test_ex01_keypoints_match_reference(submission, seed, fraction):
    demo = random_demo(seed)
    expected = reference_keypoints(demo, fraction)
    got = frame_indices(submission(MODULE).velocity_keypoints(demo, fraction), f"seed {seed}, fraction {fraction}")
    speed = demo.speed()
    missing = np.setdiff1d(expected, got)
    extra = np.setdiff1d(got, expected)
    message = [
        f"seed {seed}, fraction {fraction}, {demo.n_frames} frames: expected keypoints {fmt(expected, limit=30)}, "
        f"you returned {fmt(got, limit=30)}"
    ]
    if missing.size:
        message.append(f"these keypoints are missing from your answer:\n{describe_frames(missing, speed, fraction)}")
    if extra.size:
        message.append(f"these frames are not keypoints:\n{describe_frames(extra, speed, fraction)}")
    check(not missing.size and not extra.size, lambda: "\n".join(message))
