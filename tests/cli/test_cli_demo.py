"""``toolimit demo synth`` / ``show``: files written, summaries printed, user errors."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.cli import main
from toolimit.demos import load_demo, synthesize_demo


def test_synth_writes_the_generators_demo(capsys, tmp_path):
    out = tmp_path / "demos" / "hammer_07.npz"
    assert main(["demo", "synth", "--tool", "hammer", "--seed", "7", "--out", str(out)]) == 0
    assert "hammer" in capsys.readouterr().out
    demo = load_demo(out)
    expected = synthesize_demo("hammer", 7, fps=24.0)
    np.testing.assert_allclose(demo.head, expected.head)
    np.testing.assert_allclose(demo.handle, expected.handle)
    assert demo.fps == 24.0 and demo.tool == "hammer"


def test_synth_fps_and_show_summary(capsys, tmp_path):
    out = tmp_path / "spade.npz"
    assert main(["demo", "synth", "--tool", "spade", "--seed", "1", "--fps", "30", "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["demo", "show", str(out)]) == 0
    printed = capsys.readouterr().out
    demo = load_demo(out)
    assert f"{demo.n_frames} frames at 30 fps" in printed
    assert "keypoints (frames) [0," in printed and f"{demo.n_frames - 1}]" in printed


def test_show_says_raw_and_cleaned(capsys, repo_root):
    from toolimit.align.keypoints import velocity_keypoints
    from toolimit.demos import clean_demo

    path = repo_root / "data" / "demos" / "spade_00.npz"
    assert main(["demo", "show", str(path)]) == 0
    raw_line, clean_line = capsys.readouterr().out.splitlines()[-2:]
    raw = load_demo(path)
    cleaned, report = clean_demo(raw)
    assert raw_line.startswith("as loaded (raw): ")
    assert raw_line.endswith(f"keypoints (frames) {velocity_keypoints(raw).tolist()}")
    assert clean_line.startswith(f"cleaned, as `toolimit align` uses it ({len(report.replaced_frames)} frames replaced, "
                                 f"{len(report.head_replaced_frames)} of them with the head's position)")
    assert clean_line.endswith(f"keypoints (frames) {velocity_keypoints(cleaned).tolist()}")
    assert f"peak speed {raw.speed().max():.2f} m/s" in raw_line
    assert f"peak speed {cleaned.speed().max():.2f} m/s" in clean_line


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["demo", "synth", "--tool", "rake", "--out", "x.npz"], "rake"),
        (["demo", "synth", "--tool", "spade", "--fps", "0", "--out", "x.npz"], "--fps"),
        (["demo", "synth", "--tool", "spade", "--seed", "-3", "--out", "x.npz"], "--seed"),
        (["demo", "synth", "--tool", "spade", "--out", "x.txt"], "--out"),
        (["demo", "show", "missing.npz"], "missing.npz"),
    ],
)
def test_user_errors(capsys, tmp_path, monkeypatch, argv, fragment):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and fragment in err, err
    assert not any(tmp_path.iterdir())


def test_show_of_a_demo_too_broken_to_clean_says_so(capsys, tmp_path):
    from toolimit.demos import ToolDemo, save_demo

    rng = np.random.default_rng(0)
    head = rng.normal(size=(30, 3))
    save_demo(ToolDemo(head, head + rng.normal(size=(30, 3)), 24.0, "spade"), tmp_path / "broken.npz")
    assert main(["demo", "show", str(tmp_path / "broken.npz")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[-2].startswith("as loaded (raw): ") and lines[-1].startswith("cleaned: not possible (")
