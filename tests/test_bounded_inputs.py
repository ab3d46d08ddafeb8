"""Bounded inputs: a demonstration's frame rate, duration and frames, the synthetic generator's and
the export's rates are limited to what a video and a robot can be; each refusal is one line, exit 2,
and leaves nothing written."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from toolimit.cli import main
from toolimit.demos import ToolDemo, load_demo
from toolimit.demos.tool_demo import MAX_DURATION_S, MAX_FPS, MAX_FRAMES, MIN_FPS
from toolimit.deploy.export import RATE_RANGE_HZ
from toolimit.deploy.retime import MAX_SUBDIVISIONS
from toolimit.errors import DemoError, InputError, InvalidSetting
from toolimit.pipeline.settings import ExportSettings

MAX_RATE_HZ = RATE_RANGE_HZ[1]

REPO = Path(__file__).resolve().parents[1]
SPADE = REPO / "data" / "demos" / "spade_00.npz"


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def _demo_claiming(path: Path, fps: float, frames: int = 30) -> Path:
    """The shipped spade demonstration's first ``frames`` frames, claiming ``fps``."""
    arrays = dict(np.load(SPADE))
    arrays.update(fps=np.float64(fps), head=arrays["head"][:frames], handle=arrays["handle"][:frames])
    np.savez(path, **arrays)
    return path


def test_align_on_a_demo_claiming_a_millionth_of_a_frame_per_second_is_one_line_under_8_gb(tmp_path):
    """30 frames at 1e-6 fps were a year-long motion: alignment resampled it and was killed by the
    kernel. Under an 8 GB address-space cap the command now refuses it in one line."""
    demo = _demo_claiming(tmp_path / "slow.npz", 1e-6)
    command = ["prlimit", f"--as={8 * 1024**3}", sys.executable, "-m", "toolimit", "align", "--tool", "spade",
               "--demo", str(demo), "--out", str(tmp_path / "out"), "--quiet"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=600, cwd=tmp_path,
                          env=os.environ | {"PYTHONPATH": str(REPO)})
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "fps" in lines[0] and "1e-06" in lines[0], lines
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("fps", [1e-6, 0.5, 1e9, float("inf"), float("nan"), 0, -24])
def test_a_demo_file_with_a_frame_rate_no_video_has_is_refused(tmp_path, capsys, fps):
    demo = _demo_claiming(tmp_path / "demo.npz", fps)
    with pytest.raises(DemoError, match="fps"):
        load_demo(demo)
    assert main(["demo", "show", str(demo)]) == 2
    assert "fps" in _one_line(capsys)


@pytest.mark.parametrize("fps", ["1e9", "inf", "nan", "0", "1e-6", "1e308"])
def test_the_synthetic_generator_refuses_a_frame_rate_no_video_has(tmp_path, capsys, fps):
    out = tmp_path / "synth.npz"
    assert main(["demo", "synth", "--tool", "spade", "--fps", fps, "--out", str(out)]) == 2
    assert "--fps" in _one_line(capsys)
    assert not out.exists()


def test_the_frame_rate_bounds_hold_at_their_ends(tmp_path, capsys):
    for fps in (MIN_FPS, MAX_FPS):
        out = tmp_path / f"synth-{fps:g}.npz"
        assert main(["demo", "synth", "--tool", "spade", "--fps", str(fps), "--out", str(out)]) == 0
        assert load_demo(out).fps == fps


def test_a_demo_too_long_or_with_too_many_frames_is_refused():
    head = np.zeros((MAX_FRAMES + 1, 3))
    handle = head + [0.0, 0.0, 1.0]
    with pytest.raises(DemoError, match="too many frames"):
        ToolDemo(head, handle, MAX_FPS, "spade")
    frames = int(MAX_DURATION_S * MIN_FPS) + 2
    with pytest.raises(DemoError, match="duration"):
        ToolDemo(head[:frames], handle[:frames], MIN_FPS, "spade")


@pytest.mark.parametrize(("field", "value"), [("rate", 1e15), ("rate", float("inf")), ("rate", 1e-3),
                                              ("rate", MAX_RATE_HZ * 1.01), ("subdivisions", MAX_SUBDIVISIONS + 1)])
def test_export_rates_and_subdivisions_are_bounded(field, value):
    with pytest.raises(InvalidSetting) as error:
        ExportSettings(**{field: value})
    assert error.value.field == field
    ExportSettings(rate=MAX_RATE_HZ, subdivisions=MAX_SUBDIVISIONS)


def test_run_and_reproduce_with_a_bad_demo_write_nothing(tmp_path, capsys):
    demo = _demo_claiming(tmp_path / "spade_slow.npz", 1e-6)
    out = tmp_path / "run"
    assert main(["run", "--tool", "spade", "--robot", "planar3", "--world", "planar", "--demo", str(demo),
                 "--out", str(out), "--quick", "--quiet"]) == 2
    assert "fps" in _one_line(capsys) and not out.exists()
    out = tmp_path / "reproduce"
    assert main(["reproduce", "--preset", "quick", "--demo", str(demo), "--out", str(out), "--quiet"]) == 2
    assert "fps" in _one_line(capsys) and not out.exists()


def test_a_refused_resume_leaves_no_task_file(tmp_path):
    from toolimit.learn import shipped_task
    from toolimit.learn.training import LearningConfig, learn_policy

    out = tmp_path / "learned"
    out.mkdir()
    (out / "checkpoint.json").write_text(json.dumps({"model": "../elsewhere.safetensors", "num_timesteps": 0}))
    with pytest.raises(InputError, match="checkpoint.json"):
        learn_policy(shipped_task("spade", "planar"), out, LearningConfig(timesteps=0, envs=2), progress=False)
    assert sorted(p.name for p in out.iterdir()) == ["checkpoint.json"]


@pytest.mark.parametrize("error", [MemoryError(), OverflowError("cannot convert float infinity to integer")])
def test_memory_and_overflow_errors_from_a_users_values_are_one_line(monkeypatch, capsys, error):
    import toolimit.cli.demo as demo_command

    def fail(args):
        raise error

    monkeypatch.setattr(demo_command, "run_show", fail)
    assert main(["demo", "show", str(SPADE)]) == 2
    assert "toolimit demo: error:" in _one_line(capsys)
