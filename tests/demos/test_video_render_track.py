"""Rendering a demonstration to an MP4 and tracking its markers back (needs the [video] extra:
OpenCV), and the ``toolimit demo render | track | lift`` commands."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.cli import main
from toolimit.demos import load_demo, save_demo, synthesize_demo
from toolimit.demos.video import look_at, read_camera, read_lifted, read_tracks, side_camera, write_camera, write_tracks

cv2 = pytest.importorskip("cv2", reason="OpenCV is the [video] extra: pip install -e '.[test,compare,video]'")

from toolimit.demos.video.marker_tracking import track_markers  # noqa: E402
from toolimit.demos.video.render import render_video  # noqa: E402

#: A small side camera (640 x 360, f = 500 px: the benchmark's camera at half the resolution).
SMALL = {"width": 640, "image_height": 360, "focal": 500.0}


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    demo = synthesize_demo("spade", 0)
    camera = side_camera(demo.head, **SMALL)
    video = tmp_path_factory.mktemp("video") / "spade.mp4"
    truth = render_video(demo, camera, video)
    return demo, camera, video, truth


def test_the_tracker_finds_the_rendered_markers_within_a_pixel(rendered):
    demo, _, video, truth = rendered
    tracks = track_markers(video)
    assert tracks.n_frames == demo.n_frames
    errors = []
    for name in ("head", "handle"):
        expected, found = getattr(truth, f"{name}_visible"), getattr(tracks, f"{name}_visible")
        assert np.mean(expected == found) >= 0.95, f"{name}: visibility differs in {np.sum(expected != found)} frames"
        both = expected & found
        errors.append(np.linalg.norm(getattr(tracks, name)[both] - getattr(truth, name)[both], axis=1))
    assert np.median(np.concatenate(errors)) <= 1.0


def test_the_figure_hides_the_tool_in_some_frames_and_the_tracker_says_so(rendered):
    demo, _, video, truth = rendered
    hidden = ~truth.head_visible
    assert 0.1 * demo.n_frames < np.sum(hidden) < 0.6 * demo.n_frames
    tracks = track_markers(video)
    assert np.sum(hidden & ~tracks.head_visible) >= 0.9 * np.sum(hidden)


def test_render_track_lift_commands(tmp_path, capsys, rendered):
    demo, camera, _, _ = rendered
    demo_path, camera_path = tmp_path / "spade.npz", tmp_path / "camera.json"
    save_demo(demo, demo_path)
    write_camera(camera, camera_path)
    video = tmp_path / "out" / "spade.mp4"
    assert main(["demo", "render", str(demo_path), "--camera", str(camera_path), "--out", str(video)]) == 0
    assert video.is_file() and (tmp_path / "out" / "spade.truth.csv").is_file()
    tracks_path = tmp_path / "out" / "tracks.csv"
    assert main(["demo", "track", str(video), "--out", str(tracks_path)]) == 0
    lifted_path = tmp_path / "out" / "lifted.npz"
    argv = ["demo", "lift", str(tracks_path), "--camera", str(camera_path), "--tool", "spade", "--fps", "24"]
    assert main([*argv, "--handle-hint", "far", "--out", str(lifted_path)]) == 0
    printed = capsys.readouterr().out
    assert "working plane" in printed and "handle sides: " in printed and "if its side is right" in printed
    lifted = load_demo(lifted_path)
    assert lifted.n_frames == demo.n_frames and lifted.tool == "spade"
    assert np.mean(np.linalg.norm(lifted.head - demo.head, axis=1)) < 0.15
    record = read_lifted(lifted_path)
    assert record.arrays["head_sigma"].shape == record.arrays["side_margin"].shape == (demo.n_frames,)
    assert set(record.arrays["side_source"].tolist()) <= {"hint", "crossing", "negligible"}
    assert record.side_summary() in printed, "the printed summary is the file's"


def test_render_without_a_camera_writes_the_side_camera(tmp_path, capsys):
    demo = synthesize_demo("hammer", 1).sliced(0, 12)
    demo_path = tmp_path / "hammer.npz"
    save_demo(demo, demo_path)
    assert main(["demo", "render", str(demo_path), "--out", str(tmp_path / "h.mp4")]) == 0
    camera = read_camera(tmp_path / "h.camera.json")
    assert (camera.width, camera.height, camera.K[0, 0]) == (1280, 720, 1000.0)
    np.testing.assert_allclose(camera.centre[2], 1.2)
    assert read_tracks(tmp_path / "h.truth.csv").n_frames == 12


def _written_tracks(tmp_path, mutate) -> tuple[str, str]:
    demo = synthesize_demo("spade", 2)
    camera = look_at([0.0, -3.5, 1.2], [0.6, -0.4, 0.3])
    from toolimit.demos.video import project_demo

    tracks = mutate(project_demo(demo, camera))
    write_tracks(tracks, tmp_path / "t.csv")
    write_camera(camera, tmp_path / "c.json")
    return str(tmp_path / "t.csv"), str(tmp_path / "c.json")


@pytest.mark.parametrize(
    ("mutate", "extra", "fragment"),
    [
        (
            lambda t: type(t)(t.head, t.handle, np.arange(t.n_frames) < 5, t.handle_visible),
            [],
            "too few visible frames",
        ),
        (lambda t: t, [], "mirror ambiguity"),
        (lambda t: t, ["--handle-hint", "sideways"], "--handle-hint"),
        (lambda t: t, ["--plane-point", "1,2"], "--plane-point"),
        (lambda t: t, ["--smoothing", "-1"], "--smoothing"),
        (lambda t: t, ["--plane-normal", "1"], "--plane-normal"),
        (lambda t: t, ["--handle-hint", "near", "--plane-normal", "1,0"], "from edge-on"),
    ],
)
def test_lift_refuses_in_one_line_and_writes_nothing(tmp_path, capsys, mutate, extra, fragment):
    tracks, camera = _written_tracks(tmp_path, mutate)
    out = tmp_path / "lifted.npz"
    try:
        code = main(
            ["demo", "lift", tracks, "--camera", camera, "--tool", "spade", "--fps", "24", *extra, "--out", str(out)]
        )
    except SystemExit as exit_:  # argparse's own refusal of a flag's value
        code = exit_.code
    error = capsys.readouterr().err
    assert code == 2
    assert fragment in error and len(error.strip().splitlines()) == 1, error
    assert not out.exists() and not list(tmp_path.glob(".lifted*"))


def test_lift_refuses_a_camera_that_sees_no_ground(tmp_path, capsys):
    demo = synthesize_demo("spade", 2).translated([0.0, 0.0, 1.5])
    camera = look_at([0.0, -3.5, 1.2], [0.6, -0.4, 2.0])
    from toolimit.demos.video import project_demo

    write_tracks(project_demo(demo, camera), tmp_path / "t.csv")
    write_camera(camera, tmp_path / "c.json")
    out = tmp_path / "lifted.npz"
    argv = ["demo", "lift", str(tmp_path / "t.csv"), "--camera", str(tmp_path / "c.json"), "--tool", "spade"]
    assert main([*argv, "--fps", "24", "--handle-hint", "near", "--out", str(out)]) == 2
    assert "camera sees no ground" in capsys.readouterr().err and not out.exists()


def test_track_refuses_a_file_that_is_not_a_video(tmp_path, capsys):
    fake = tmp_path / "fake.mp4"
    fake.write_text("not a video")
    assert main(["demo", "track", str(fake), "--out", str(tmp_path / "t.csv")]) == 2
    error = capsys.readouterr().err
    assert "fake.mp4" in error and len(error.strip().splitlines()) == 1
    assert not (tmp_path / "t.csv").exists()
