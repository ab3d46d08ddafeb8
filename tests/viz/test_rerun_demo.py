"""Demonstration recordings: every named demonstration's speed, keypoints and paths land in the file."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from toolimit.demos import synthesize_demo
from toolimit.viz.rerun_demo import save_demo_recording

RERUN_CLI = Path(sys.executable).parent / "rerun"


def test_each_demonstration_is_recorded(tmp_path, monkeypatch):
    monkeypatch.delenv("RERUN", raising=False)
    demos = {"raw": synthesize_demo("spade", seed=0), "clean": synthesize_demo("spade", seed=0, noise=False)}
    path = save_demo_recording(tmp_path / "demo.rrd", demos)
    assert path == tmp_path / "demo.rrd"
    printed = subprocess.run([RERUN_CLI, "rrd", "print", path], capture_output=True, text=True, timeout=60)
    assert printed.returncode == 0, printed.stderr
    for name in demos:
        for entity in (f"speed/{name}", f"speed/{name}_keypoints", f"world/{name}/head", f"world/{name}/keypoints"):
            assert entity in printed.stdout


def test_no_demonstration_is_refused(tmp_path):
    with pytest.raises(ValueError, match="at least one demonstration"):
        save_demo_recording(tmp_path / "demo.rrd", {})
