"""Demo files: round trip, clear errors on bad input, the real aligned trajectories."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

from toolimit.demos import DemoError, ToolDemo, load_demo, load_video_trajectory, save_demo
from toolimit.demos.cleaning import step_axis_rates


def _demo(n: int = 30) -> ToolDemo:
    t = np.linspace(0.0, 1.0, n)
    head = np.stack([t, 0.1 * np.sin(3 * t), 0.2 + 0.05 * t], axis=1)
    return ToolDemo(head, head + [0.0, 0.0, 0.4], 24.0, "spade", source="test")


def _write(path, **arrays) -> None:
    np.savez(path, **arrays)


def test_round_trip_keeps_arrays_and_extra_keys(tmp_path):
    demo = _demo()
    path = tmp_path / "demo.npz"
    save_demo(demo, path, clean_head=demo.head + 1.0, outlier_frames=np.array([3, 4]))
    loaded = load_demo(path)
    np.testing.assert_array_equal(loaded.head, demo.head)
    np.testing.assert_array_equal(loaded.handle, demo.handle)
    assert (loaded.fps, loaded.tool, loaded.source) == (24.0, "spade", "test")
    with np.load(path) as raw:
        np.testing.assert_array_equal(raw["clean_head"], demo.head + 1.0)
        assert raw["fps"].shape == () and raw["tool"].shape == ()
    assert not list(tmp_path.glob(".*")), "no temporary file may be left behind"


def test_save_is_byte_reproducible(tmp_path):
    save_demo(_demo(), tmp_path / "a.npz")
    save_demo(_demo(), tmp_path / "b.npz")
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()


def test_save_refuses_reserved_extra_key(tmp_path):
    with pytest.raises(DemoError, match="reuse the demo keys"):
        save_demo(_demo(), tmp_path / "a.npz", head=np.zeros(3))
    assert not (tmp_path / "a.npz").exists()


def test_save_refuses_object_arrays_and_leaves_no_file(tmp_path):
    with pytest.raises(DemoError, match="extra array 'meta' has dtype object"):
        save_demo(_demo(), tmp_path / "a.npz", meta=np.array([{"a": 1}], dtype=object))
    assert list(tmp_path.iterdir()) == []


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.npz"):
        load_demo(tmp_path / "nope.npz")


def test_unknown_file_type(tmp_path):
    path = tmp_path / "demo.csv"
    path.write_text("1,2,3\n")
    with pytest.raises(DemoError, match=r"demo\.csv.*unknown demonstration file type '\.csv'"):
        load_demo(path)


def test_not_a_zip(tmp_path):
    path = tmp_path / "broken.npz"
    path.write_bytes(b"not a zip at all")
    with pytest.raises(DemoError, match="broken.npz: cannot read as .npz"):
        load_demo(path)


def test_unknown_keys(tmp_path):
    path = tmp_path / "odd.npz"
    _write(path, positions=np.zeros((20, 3)), fps=24.0)
    with pytest.raises(DemoError, match=r"odd\.npz: not a demonstration: keys \['fps', 'positions'\]"):
        load_demo(path)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"handle": None}, "missing key 'handle'"),
        ({"fps": None}, "missing key 'fps'"),
        ({"tool": None}, "missing key 'tool'"),
        ({"head": np.zeros((30, 2))}, r"key 'head' must have shape \(T, 3\), got \(30, 2\)"),
        ({"fps": np.array([24.0, 24.0])}, "key 'fps' must be a numeric scalar"),
        ({"fps": -1.0}, "key 'fps' must be between 1 and 1000 frames per second"),
        ({"tool": np.array([1, 2])}, "key 'tool' must be a string scalar"),
        ({"handle": np.zeros((20, 3))}, r"head \(30, 3\) and handle \(20, 3\) have different shapes"),
        ({"head": np.array(["a"] * 90).reshape(30, 3)}, "key 'head' must be numeric"),
    ],
)
def test_bad_project_files(tmp_path, change, message):
    demo = _demo()
    arrays = {"head": demo.head, "handle": demo.handle, "fps": 24.0, "tool": "spade"}
    for key, value in change.items():
        if value is None:
            arrays.pop(key)
        else:
            arrays[key] = value
    path = tmp_path / "bad.npz"
    _write(path, **arrays)
    with pytest.raises(DemoError, match=message) as error:
        load_demo(path)
    assert "bad.npz" in str(error.value)


def test_nan_is_reported_with_key_and_frame(tmp_path):
    demo = _demo()
    head = demo.head.copy()
    head[7, 1] = np.nan
    _write(tmp_path / "nan.npz", head=head, handle=demo.handle, fps=24.0, tool="spade")
    with pytest.raises(DemoError, match=r"nan\.npz: key 'head' has NaN or inf at frames \[7\]"):
        load_demo(tmp_path / "nan.npz")


def test_too_few_frames_in_file(tmp_path):
    head = np.zeros((9, 3))
    _write(tmp_path / "short.npz", head=head, handle=head + [0, 0, 0.4], fps=24.0, tool="spade")
    with pytest.raises(DemoError, match=r"short\.npz: too few frames: 9"):
        load_demo(tmp_path / "short.npz")


def test_zero_length_tool(tmp_path):
    demo = _demo()
    _write(tmp_path / "zero.npz", head=demo.head, handle=demo.head, fps=24.0, tool="spade")
    with pytest.raises(DemoError, match=r"zero\.npz: tool length 0\.0000 m at frame 0"):
        load_demo(tmp_path / "zero.npz")


def test_tool_mismatch(tmp_path):
    save_demo(_demo(), tmp_path / "d.npz")
    with pytest.raises(DemoError, match="tool='hammer' was asked but the file shows a 'spade'"):
        load_demo(tmp_path / "d.npz", tool="hammer")


def test_member_timestamps_are_fixed(tmp_path):
    save_demo(_demo(), tmp_path / "d.npz")
    with zipfile.ZipFile(tmp_path / "d.npz") as archive:
        assert {info.date_time for info in archive.infolist()} == {(1980, 1, 1, 0, 0, 0)}


def test_video_trajectory_errors(tmp_path):
    position = np.zeros((20, 3))
    quaternion = np.tile([1.0, 0, 0, 0], (20, 1))
    _write(tmp_path / "spade_q.npz", tip_position=position, tip_quaternion_wxyz=quaternion[:, :3], fps=24)
    with pytest.raises(DemoError, match=r"spade_q\.npz: key 'tip_quaternion_wxyz' must have shape \(T, 4\)"):
        load_demo(tmp_path / "spade_q.npz")
    _write(tmp_path / "spade_n.npz", tip_position=position, tip_quaternion_wxyz=2 * quaternion, fps=24)
    with pytest.raises(DemoError, match="row 0 is not a unit quaternion"):
        load_demo(tmp_path / "spade_n.npz")
    _write(tmp_path / "thing.npz", tip_position=position, tip_quaternion_wxyz=quaternion, fps=24)
    with pytest.raises(DemoError, match=r"thing\.npz: the file does not say which tool"):
        load_demo(tmp_path / "thing.npz")
    assert load_demo(tmp_path / "thing.npz", tool="spade").n_frames == 20


# --- the real data -----------------------------------------------------------------------------
def test_real_spade_handle_distance(video_demos_dir):
    demo, tip, params = load_video_trajectory(video_demos_dir / "spade_video1_aligned.npz")
    np.testing.assert_allclose(demo.lengths, 0.4026, atol=5e-4)
    assert demo.tool == "spade" and demo.fps == 24 and demo.n_frames == 92
    np.testing.assert_allclose(tip.position, demo.head)
    np.testing.assert_allclose(np.linalg.det(tip.rotation), 1.0, atol=1e-9)
    assert params["goal_box_position"].shape == (3,)
    assert {"sand_buffer_position", "sand_buffer_yaw"} <= set(params)
    # The file's known orientation flips show up as jumps of the tool axis.
    rates = step_axis_rates(demo)
    assert np.all(rates[[19, 35, 82, 90]] > 12.0)


def test_real_spade_example_and_poses_agree(video_demos_dir):
    aligned = load_demo(video_demos_dir / "spade_example_aligned.npz")
    assert aligned.n_frames == 92 and aligned.tool == "spade"
    # The poses file has no fps; it samples the same motion twice as densely.
    with pytest.raises(DemoError, match="missing key 'fps'.*pass fps="):
        load_demo(video_demos_dir / "spade_example_poses.npz")
    poses = load_demo(video_demos_dir / "spade_example_poses.npz", fps=48)
    assert poses.n_frames == 184
    assert np.linalg.norm(poses.head[0] - aligned.head[0]) < 0.01


def test_real_hammer(video_demos_dir):
    demo, tip, params = load_video_trajectory(video_demos_dir / "hammer_video1_aligned.npz")
    assert demo.tool == "hammer" and demo.n_frames == 97
    np.testing.assert_allclose(demo.lengths, 0.33, atol=1e-9)
    assert params["nail_position"].shape == (3,)
    axis = params["handle_axis_in_tip_frame"]
    assert sorted(np.abs(axis).tolist()) == [0.0, 0.0, 1.0]
    # The chosen handle axis is the tip-frame axis least aligned with the head's fast motion.
    velocity = np.gradient(demo.head, demo.dt, axis=0)
    weight = np.sum(velocity**2, axis=1)
    unit = velocity / np.linalg.norm(velocity, axis=1, keepdims=True)
    chosen = np.sum(weight * np.abs(np.sum(demo.axis * unit, axis=1)))
    for k in range(3):
        other = np.sum(weight * np.abs(np.sum(tip.rotation[:, :, k] * unit, axis=1)))
        assert chosen <= other + 1e-9


def test_real_joint_file_is_not_a_demo(video_demos_dir):
    with pytest.raises(DemoError, match=r"spade_example_panda_q\.npz: not a demonstration: keys \['fps', 'q'\]"):
        load_demo(video_demos_dir / "spade_example_panda_q.npz")
