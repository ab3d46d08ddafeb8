"""save_recording: the log function's entities land in the file, nothing is written under RERUN=off."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import rerun as rr

from toolimit.viz.rerun_file import save_recording

RERUN_CLI = Path(sys.executable).parent / "rerun"


def log_two_points(recording: rr.RecordingStream) -> None:
    recording.log("world/points", rr.Points3D([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), static=True)


def test_the_logged_entities_are_in_the_file(tmp_path, monkeypatch):
    monkeypatch.delenv("RERUN", raising=False)
    path = save_recording(tmp_path / "points.rrd", log_two_points)
    assert path == tmp_path / "points.rrd" and path.is_file()
    printed = subprocess.run([RERUN_CLI, "rrd", "print", path], capture_output=True, text=True, timeout=60)
    assert printed.returncode == 0, printed.stderr
    assert "world/points" in printed.stdout
    assert [p.name for p in tmp_path.iterdir()] == ["points.rrd"]  # no temporary file left


def test_rerun_off_writes_nothing_and_logs_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("RERUN", "off")
    calls = []
    assert save_recording(tmp_path / "off.rrd", calls.append) is None
    assert not calls and not list(tmp_path.iterdir())
