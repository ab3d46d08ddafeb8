"""The alignment's rerun recording: written atomically, readable back, skipped under RERUN=off."""

from __future__ import annotations

import subprocess
import sys

from align_fake_scene import FakeTargetScene, make_demo

from toolimit.align.config import AlignmentConfig
from toolimit.align.search import align
from toolimit.viz.rerun_alignment import save_alignment_recording


def small_result():
    config = AlignmentConfig(samples=200, candidates=1, replays=3, element_std=0.05, ground_tolerance=10.0)
    return align(make_demo(), "spade", "planar", config, seed=1, progress=False, scene_factory=FakeTargetScene)


def test_recording_holds_demo_keypoints_scene_and_replay(tmp_path, monkeypatch):
    monkeypatch.delenv("RERUN", raising=False)
    result = small_result()
    assert result.best is not None
    path = save_alignment_recording(result, tmp_path / "align.rrd", scene=FakeTargetScene())
    assert path == tmp_path / "align.rrd" and path.stat().st_size > 1000
    assert [p.name for p in tmp_path.iterdir()] == ["align.rrd"]  # no temporary file left
    printed = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "print", str(path)], capture_output=True, text=True, timeout=120
    ).stdout
    for entity in ("/demo/head", "/demo/keypoints", "/scene/params/target", "/replay/tool", "/replay/state/target"):
        assert entity in printed, f"{entity} missing from the recording"


def test_rerun_off_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("RERUN", "off")
    assert save_alignment_recording(small_result(), tmp_path / "off.rrd", scene=FakeTargetScene()) is None
    assert not any(tmp_path.iterdir())
