"""rerun recordings of 3D world replays: written, loadable by rerun, disabled by RERUN=off."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from toolimit.scenes.spatial.hammer import SpatialHammerScene
from toolimit.tools import ToolPose
from toolimit.viz.meshcat_views import replay_scene
from toolimit.viz.rerun_world import save_replay_recording

RERUN_CLI = Path(sys.executable).parent / "rerun"
FACE_DOWN = np.column_stack([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


@pytest.fixture(scope="module")
def hammer_frames():
    n = 8
    z = 0.3 + 0.055 + np.linspace(0.15, -0.01, n)
    position = np.column_stack([np.full(n, 0.5), np.full(n, 0.2), z])
    poses = ToolPose(position, np.broadcast_to(FACE_DOWN, (n, 3, 3)).copy())
    params = {"nail_position": np.array([0.5, 0.2, 0.3])}
    return replay_scene(SpatialHammerScene(), poses, params, np.random.default_rng(0))


def test_recording_is_written_and_loads_in_rerun(tmp_path, hammer_frames, monkeypatch):
    monkeypatch.delenv("RERUN", raising=False)
    path = save_replay_recording(tmp_path / "hammer.rrd", hammer_frames, "hammer")
    assert path == tmp_path / "hammer.rrd" and path.stat().st_size > 1000
    verified = subprocess.run([RERUN_CLI, "rrd", "verify", path], capture_output=True, text=True, timeout=60)
    assert verified.returncode == 0, verified.stderr
    printed = subprocess.run([RERUN_CLI, "rrd", "print", path], capture_output=True, text=True, timeout=60).stdout
    for entity in ("world/board", "world/nail", "world/tool", "world/tool/shapes/boxes", "world/tool_path"):
        assert entity in printed


def test_rerun_off_writes_nothing(tmp_path, hammer_frames, monkeypatch):
    monkeypatch.setenv("RERUN", "off")
    assert save_replay_recording(tmp_path / "off.rrd", hammer_frames, "hammer") is None
    assert not list(tmp_path.iterdir())


def test_empty_replay_is_an_error(tmp_path):
    with pytest.raises(ValueError, match="at least one frame"):
        save_replay_recording(tmp_path / "empty.rrd", [], "hammer")
