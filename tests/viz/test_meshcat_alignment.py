"""The --html view of an alignment: the best hammer candidate replayed drives the nail home."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from toolimit.align.config import AlignmentConfig
from toolimit.align.search import align
from toolimit.demos.tool_demo import ToolDemo
from toolimit.viz.meshcat_alignment import save_alignment_html


def strike_demo() -> ToolDemo:
    """A hammer head falling at 3 m/s from 0.6 m to 0.25 m, then lifted (24 fps)."""
    fps, frames = 24.0, 30
    t = np.arange(frames) / fps
    z = np.where(t < 0.4, 0.6, np.maximum(0.6 - 3.0 * (t - 0.4), 0.25))
    z = np.where(t > 0.75, 0.25 + 2.0 * (t - 0.75), z)
    head = np.column_stack([np.full(frames, 0.5), np.zeros(frames), z])
    return ToolDemo(head=head, handle=head + [-0.3, 0.0, 0.1], fps=fps, tool="hammer", source="synthetic strike")


@pytest.fixture(scope="module")
def result():
    config = AlignmentConfig(samples=200, candidates=1, replays=1, accept_replays=1)
    return align(strike_demo(), "hammer", "3d", config, seed=0, progress=False, clean=False)  # exact by construction


def test_best_candidate_replay_as_html(tmp_path, result, html_commands):
    assert result.best is not None, "the synthetic strike should plant the nail for some sample"
    path = save_alignment_html(result, tmp_path / "best.html")
    commands = html_commands(path)
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in animation["animations"]}
    plate = clips["/meshcat/world/nail/plate"]["tracks"][0]["keys"]
    assert len(plate) == result.demo.n_frames
    assert plate[-1]["value"][2] < plate[0]["value"][2] - 0.04  # the replay drives the nail ~5 cm
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    assert sum(p.startswith("/meshcat/targets/") for p in objects) == len(result.keypoints)


def test_planar_alignments_and_empty_searches_are_refused(tmp_path, result):
    with pytest.raises(ValueError, match="3D worlds"):
        save_alignment_html(dataclasses.replace(result, world="planar"), tmp_path / "x.html")
    with pytest.raises(ValueError, match="no candidate"):
        save_alignment_html(dataclasses.replace(result, candidates=[]), tmp_path / "x.html")
    assert not list(tmp_path.iterdir())
