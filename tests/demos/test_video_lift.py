"""The lift from 2D tracks to a demonstration: exact synthetic cases, every refusal, the file formats,
and the real trajectories seen by the benchmark's side camera (skipped without ../shared)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from toolimit.demos import ToolDemo, load_video_trajectory, save_demo
from toolimit.demos.video import (
    TRACKS_HEADER,
    EndpointTracks,
    LiftSettings,
    handle_side,
    lift_tracks,
    look_at,
    perturbed,
    project_demo,
    ray_plane_intersection,
    read_camera,
    read_lifted,
    read_tracks,
    side_camera,
    write_camera,
    write_lifted,
    write_tracks,
)
from toolimit.demos.video.lift import (
    PIXEL_WIDTHS,
    SWITCH_EVIDENCE,
    _filter_diagonal,
    _filtered,
    choose_sides,
    cross_validated_width,
)
from toolimit.errors import DemoError, InvalidSetting, TrackError

EXACT = LiftSettings(smoothing=0.0, offset_smoothing=0.0)
#: A camera 1.2 m high at the origin, looking along +x at the working plane x = 3.
CAMERA = look_at([0.0, 0.0, 1.2], [3.0, 0.0, 0.4])


def planar_demo(tilt_towards_camera: float, frames: int = 40) -> ToolDemo:
    """A head moving in the plane x = 3, resting on the ground (z = 0) in its second half, with a 0.4 m
    tool leaning ``tilt_towards_camera`` radians out of the plane towards the camera (-x)."""
    t = np.linspace(0.0, 1.0, frames)
    head = np.column_stack([np.full(frames, 3.0), -0.6 + 1.2 * t, 0.3 * np.clip(np.sin(2 * np.pi * t), 0.0, None)])
    up = np.column_stack([np.zeros(frames), 0.3 * np.ones(frames), np.ones(frames)])
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    axis = np.cos(tilt_towards_camera) * up + np.sin(tilt_towards_camera) * np.array([-1.0, 0.0, 0.0])
    return ToolDemo(head, head + 0.4 * axis, 24.0, "spade")


def held_still(frames: int = 20) -> ToolDemo:
    """A 0.4 m tool held still with its head on the ground at (3, 0, 0), leaning 0.5 rad towards the
    camera: its mirror image is just as still, so only a hint can tell them apart."""
    axis = np.array([-np.sin(0.5), 0.0, np.cos(0.5)])
    head = np.tile([3.0, 0.0, 0.0], (frames, 1))
    return ToolDemo(head, head + 0.4 * axis, 24.0, "spade")


def test_ray_plane_intersection_by_hand():
    rays = np.array([[1.0, 0.0, 0.0], [0.6, 0.8, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    points = ray_plane_intersection(np.array([1.0, 2.0, 3.0]), rays, np.array([1.0, 0.0, 0.0]), 2.0)
    np.testing.assert_allclose(points[:2], [[3.0, 2.0, 3.0], [3.0, 2.0 + 8 / 3, 3.0]])
    assert np.all(np.isnan(points[2:])), "a ray parallel to the plane or pointing away meets it nowhere"


def test_projection_and_rays_invert_each_other():
    points = np.array([[3.0, 0.2, 0.1], [2.5, -0.7, 1.5]])
    pixels, depth = CAMERA.project(points)
    rays = CAMERA.rays(pixels)
    along = (points - CAMERA.centre) / np.linalg.norm(points - CAMERA.centre, axis=1, keepdims=True)
    np.testing.assert_allclose(rays, along, atol=1e-12)
    assert np.all(depth > 0)


def test_a_planar_motion_is_lifted_exactly():
    demo = planar_demo(0.5)
    lifted = lift_tracks(
        project_demo(demo, CAMERA),
        CAMERA,
        "spade",
        24.0,
        LiftSettings(handle_hint="near", smoothing=0.0, offset_smoothing=0.0),
    )
    np.testing.assert_allclose(lifted.plane_distance, 3.0, atol=1e-9)
    np.testing.assert_allclose(lifted.demo.head, demo.head, atol=1e-9)
    np.testing.assert_allclose(lifted.demo.handle, demo.handle, atol=1e-9)
    assert not lifted.handle_far.any()
    assert not lifted.head_filled.any() and np.all(lifted.head_sigma > 0)


def test_handle_side_reads_the_hint_off_a_known_motion():
    assert handle_side(planar_demo(0.5), CAMERA) == "near"
    assert handle_side(planar_demo(-0.5), CAMERA) == "far"


@pytest.mark.parametrize("hint", ["near", "far"])
def test_the_hint_decides_a_mirror_ambiguity(hint):
    demo = held_still()
    lifted = lift_tracks(
        project_demo(demo, CAMERA),
        CAMERA,
        "spade",
        24.0,
        LiftSettings(handle_hint=hint, smoothing=0.0, offset_smoothing=0.0),
    )
    assert lifted.hint_used
    np.testing.assert_allclose(lifted.demo.head, demo.head, atol=1e-9)
    if hint == "near":
        np.testing.assert_allclose(lifted.demo.handle, demo.handle, atol=1e-9)
        return
    assert lifted.handle_far.all()
    assert np.all(lifted.demo.handle[:, 0] > 3.0), "the far solution leans away from the camera"
    np.testing.assert_allclose(lifted.demo.lengths, 0.4, atol=1e-9)


def test_a_known_plane_point_replaces_the_ground():
    demo = planar_demo(0.5).translated([0.0, 0.0, 0.5])  # the head never touches the ground
    settings = LiftSettings(handle_hint="near", smoothing=0.0, offset_smoothing=0.0, plane_point=(3.0, 5.0, -1.0))
    lifted = lift_tracks(project_demo(demo, CAMERA), CAMERA, "spade", 24.0, settings)
    np.testing.assert_allclose(lifted.demo.head, demo.head, atol=1e-9)
    # without the point, the lowest head is taken for a ground contact: the plane comes too far, where
    # no tool of its length joins the head to its handle's rays, and the lift says so
    with pytest.raises(TrackError, match="the working plane does not fit: in 40 of 40 frames"):
        lift_tracks(project_demo(demo, CAMERA), CAMERA, "spade", 24.0, LiftSettings(handle_hint="near"))


def test_the_hint_holds_where_smoothness_would_overrule_it():
    # The true motion leans towards the camera (near), and its mirror image's handle path is rougher
    # by more than the 1.5 times the lift used to call unambiguous: smoothness would choose near.
    # Told "far", the lift keeps far in every frame: nothing in the image contradicts it.
    demo = planar_demo(0.5)
    near, far = _candidates(demo)
    roughness = [float(np.sum(np.diff(path, n=2, axis=0) ** 2)) for path in (near, far)]
    assert roughness[1] > 1.5 * roughness[0]
    lifted = lift_tracks(project_demo(demo, CAMERA), CAMERA, "spade", 24.0, replace(EXACT, handle_hint="far"))
    assert lifted.handle_far.all() and lifted.hint_used
    assert set(lifted.side_source.tolist()) == {"hint"}
    np.testing.assert_allclose(lifted.demo.handle, far, atol=1e-9)
    right = lift_tracks(project_demo(demo, CAMERA), CAMERA, "spade", 24.0, replace(EXACT, handle_hint="near"))
    np.testing.assert_allclose(right.demo.handle, demo.handle, atol=1e-9)


def test_the_per_frame_side_record():
    demo = planar_demo(0.5)
    tracks = perturbed(project_demo(demo, CAMERA), 1.0, 0.1, seed=2)
    lifted = lift_tracks(tracks, CAMERA, "spade", 24.0, LiftSettings(handle_hint="near"))
    assert lifted.side_source.shape == lifted.side_margin.shape == lifted.mirror_distance.shape == (demo.n_frames,)
    # only the hint holds each frame: no evidence from the image
    assert set(lifted.side_source.tolist()) == {"hint"} and not lifted.side_margin.any()
    # the mirror solution is twice the depth offset away: the error of a wrong side
    near, far = _candidates(demo)
    true_separation = np.linalg.norm(far - near, axis=1)
    assert np.median(np.abs(lifted.mirror_distance - true_separation)) < 0.03
    assert np.median(lifted.mirror_distance) > 10 * np.median(lifted.handle_sigma)


def turning_through_the_ray(frames: int = 48) -> ToolDemo:
    """A head sliding along the plane x = 3 on the ground, its 0.4 m tool turning from 0.7 rad
    towards the camera to 0.7 rad away from it: the handle end crosses from near to far."""
    t = np.linspace(0.0, 1.0, frames)
    head = np.column_stack([np.full(frames, 3.0), -0.3 + 0.6 * t, np.zeros(frames)])
    tilt = 0.7 - 1.4 * t
    axis = np.column_stack([-np.sin(tilt), np.zeros(frames), np.cos(tilt)])
    return ToolDemo(head, head + 0.4 * axis, 24.0, "spade")


@pytest.mark.parametrize("hint", ["near", "far"])
def test_a_frame_leaves_the_hint_only_at_a_clear_zero_crossing(hint):
    # depth offsets (m) of a handle end crossing the head's foot at frame 12 (a V) at 5 cm a frame, to 1 cm
    frames = np.arange(30)
    offset = np.abs(0.05 * (frames - 12.0))
    points = np.zeros((30, 3))
    sides = choose_sides(points, points, offset, np.full(30, 0.01), hint)
    # most frames (13-29) keep the hint; frames 0-11 are across a crossing of evidence >= 5 sigma
    assert np.all(sides.far[13:] == (hint == "far")) and np.all(sides.far[:12] != (hint == "far"))
    assert set(sides.source[:12].tolist()) == {"crossing"} and set(sides.source[13:].tolist()) == {"hint"}
    assert np.all(sides.margin[:12] >= SWITCH_EVIDENCE) and not sides.margin[13:].any()
    # the same within its noise of 10 cm: no evidence, the hint holds every frame
    noisy = choose_sides(points, points, offset, np.full(30, 0.1), hint)
    assert np.all(noisy.far == (hint == "far")) and set(noisy.source.tolist()) == {"hint"}
    # a tangent touch (a U) is no crossing
    touch = choose_sides(points, points, 0.005 * (frames - 12.0) ** 2, np.full(30, 0.01), hint)
    assert np.all(touch.far == (hint == "far"))


def test_without_a_hint_a_mirror_ambiguity_is_refused():
    for demo in (planar_demo(0.5), turning_through_the_ray()):
        with pytest.raises(TrackError, match="mirror ambiguity.*--handle-hint near|far"):
            lift_tracks(project_demo(demo, CAMERA), CAMERA, "spade", 24.0, EXACT)


def test_a_given_plane_normal_turns_the_working_plane():
    # the head moves in the vertical plane through (3, 0) turned 40 deg from facing the camera
    frames = 40
    t = np.linspace(0.0, 1.0, frames)
    along = np.array([np.sin(np.radians(40)), np.cos(np.radians(40)), 0.0])
    head = np.array([3.0, 0.0, 0.0]) + (-0.5 + t)[:, None] * along
    head[:, 2] = 0.3 * np.clip(np.sin(2 * np.pi * t), 0.0, None)
    demo = ToolDemo(head, head + [0.0, 0.0, 0.4], 24.0, "spade")
    normal = (float(np.cos(np.radians(40))), float(-np.sin(np.radians(40))))
    settings = replace(EXACT, handle_hint="near", plane_point=(3.0, 0.0, 0.0))
    turned = lift_tracks(project_demo(demo, CAMERA), CAMERA, "spade", 24.0, replace(settings, plane_normal=normal))
    np.testing.assert_allclose(turned.demo.head, demo.head, atol=1e-9)
    facing = lift_tracks(project_demo(demo, CAMERA), CAMERA, "spade", 24.0, settings)
    assert np.max(np.linalg.norm(facing.demo.head - demo.head, axis=1)) > 0.2
    with pytest.raises(TrackError, match="from edge-on"):
        lift_tracks(project_demo(demo, CAMERA), CAMERA, "spade", 24.0, replace(settings, plane_normal=(0.0, 1.0)))


def turned_planar_motion(turn_degrees: float, frames: int = 48) -> ToolDemo:
    """A 0.4 m tool in rigid planar motion: its head moves in the vertical plane through (3, 0) whose
    normal is turned ``turn_degrees`` from the camera's (+x), touching the ground in its middle; the
    tool leans 0.5 rad out of that plane, towards the camera, and turns 1 rad within it."""
    t = np.linspace(0.0, 1.0, frames)
    turn = np.radians(turn_degrees)
    normal = np.array([np.cos(turn), np.sin(turn), 0.0])
    along = np.array([-np.sin(turn), np.cos(turn), 0.0])
    head = np.array([3.0, 0.0, 0.0]) + (-0.5 + t)[:, None] * along
    head[:, 2] = 0.3 * np.abs(np.cos(np.pi * t))
    phi = -0.5 + t
    in_plane = np.sin(phi)[:, None] * along + np.cos(phi)[:, None] * np.array([0.0, 0.0, 1.0])
    axis = np.cos(0.5) * in_plane - np.sin(0.5) * normal
    return ToolDemo(head, head + 0.4 * axis, 24.0, "spade")


def test_the_plane_turn_is_fitted_from_a_planar_motion():
    demo = turned_planar_motion(-40.0)
    tracks = project_demo(demo, CAMERA)
    settings = replace(EXACT, handle_hint="near", plane_point=(3.0, 0.0, 0.0))
    fitted = lift_tracks(tracks, CAMERA, "spade", 24.0, replace(settings, fit_plane_normal=True))
    assert fitted.plane_turn == pytest.approx(-40.0, abs=1e-6)
    np.testing.assert_allclose(fitted.demo.head, demo.head, atol=1e-9)
    np.testing.assert_allclose(fitted.demo.handle, demo.handle, atol=1e-9)
    facing = lift_tracks(tracks, CAMERA, "spade", 24.0, settings)
    assert facing.plane_turn == pytest.approx(0.0, abs=1e-9)
    assert np.max(np.linalg.norm(facing.demo.head - demo.head, axis=1)) > 0.2
    # 1 px of noise: within two steps of the turns tried, the head far nearer than facing the camera
    noisy = perturbed(tracks, 1.0, 0.05, seed=3)
    fitted = lift_tracks(noisy, CAMERA, "spade", 24.0, replace(settings, smoothing=None, fit_plane_normal=True))
    assert abs(fitted.plane_turn + 40.0) <= 10.0
    errors = [np.mean(np.linalg.norm(lifted.demo.head - demo.head, axis=1)) for lifted in (fitted, facing)]
    assert errors[0] < errors[1] / 3
    with pytest.raises(InvalidSetting, match="fit_plane_normal"):
        LiftSettings(plane_normal=(1.0, 0.0), fit_plane_normal=True)


def test_the_lifted_file_round_trips_and_names_a_foreign_file(tmp_path):
    demo = planar_demo(0.5)
    lifted = lift_tracks(project_demo(demo, CAMERA), CAMERA, "spade", 24.0, replace(EXACT, handle_hint="near"))
    write_lifted(lifted, lifted.demo, tmp_path / "lifted.npz")
    record = read_lifted(tmp_path / "lifted.npz")
    np.testing.assert_allclose(record.demo.handle, demo.handle, atol=1e-9)
    assert record.arrays["side_source"].tolist() == lifted.side_source.tolist()
    np.testing.assert_allclose(record.arrays["side_margin"], lifted.side_margin)
    assert record.side_summary().startswith(f"handle sides: {demo.n_frames} frames from the hint, 0 left it")
    save_demo(demo, tmp_path / "plain.npz")
    with pytest.raises(DemoError, match="missing key 'head_sigma': not a file written by `toolimit demo lift`"):
        read_lifted(tmp_path / "plain.npz")


def _candidates(demo: ToolDemo) -> tuple[np.ndarray, np.ndarray]:
    """The near and far handle solutions of ``demo`` seen by CAMERA."""
    from toolimit.demos.video.lift import handle_candidates

    near, far, _ = handle_candidates(CAMERA.centre, CAMERA.rays(CAMERA.project(demo.handle)[0]), demo.head, 0.4)
    return near, far


def test_dropped_frames_are_filled_and_flagged():
    demo = planar_demo(0.5)
    tracks = project_demo(demo, CAMERA)
    hidden = np.zeros(demo.n_frames, dtype=bool)
    hidden[[5, 6, 20]] = True
    tracks = EndpointTracks(tracks.head, tracks.handle, ~hidden, tracks.handle_visible & ~hidden)
    lifted = lift_tracks(
        tracks, CAMERA, "spade", 24.0, LiftSettings(handle_hint="near", smoothing=0.0, offset_smoothing=0.0)
    )
    assert lifted.head_filled.tolist() == hidden.tolist()
    seen = ~hidden
    np.testing.assert_allclose(lifted.demo.head[seen], demo.head[seen], atol=1e-9)
    assert np.max(np.linalg.norm(lifted.demo.head - demo.head, axis=1)) < 0.05
    np.testing.assert_allclose(lifted.demo.lengths, 0.4, atol=1e-9)


def test_uncertainty_grows_with_pixel_noise_and_distance():
    demo = planar_demo(0.5)
    tracks = project_demo(demo, CAMERA)
    small = lift_tracks(tracks, CAMERA, "spade", 24.0, LiftSettings(handle_hint="near", pixel_noise=1.0))
    large = lift_tracks(tracks, CAMERA, "spade", 24.0, LiftSettings(handle_hint="near", pixel_noise=4.0))
    assert np.all(large.head_sigma > small.head_sigma)
    # 1 px at 3 m and f = 1000 px moves a point about 3 mm across the ray, and more along it
    assert 0.003 < np.median(small.head_sigma) < 0.05


def _spread_over_draws(demo: ToolDemo, settings: LiftSettings, noise: float, draws: int = 100):
    """The lift of ``draws`` noisy copies of ``demo``'s tracks: per frame, the root mean square error
    of head and handle end (m), the last lift, and the mean tool-axis error (degrees)."""
    exact = project_demo(demo, CAMERA)
    head, handle, axis = [], [], []
    for seed in range(draws):
        lifted = lift_tracks(perturbed(exact, noise, 0.0, seed), CAMERA, "spade", 24.0, settings)
        head.append(np.linalg.norm(lifted.demo.head - demo.head, axis=1))
        handle.append(np.linalg.norm(lifted.demo.handle - demo.handle, axis=1))
        axis.append(np.degrees(np.arccos(np.clip(np.sum(lifted.demo.axis * demo.axis, axis=1), -1.0, 1.0))))
    rms = [np.sqrt(np.mean(np.square(errors), axis=0)) for errors in (head, handle)]
    return rms[0], rms[1], lifted, float(np.mean(axis))


@pytest.mark.parametrize("tilt", [0.0, 0.5])
def test_uncertainty_matches_the_spread_over_noise_draws(tilt):
    # tilt 0: the tool seen side-on, its handle's ray tangent to the sphere of the tool's length in
    # every frame (where a finite difference clamped at the tangent reported too little)
    demo = planar_demo(tilt)
    settings = LiftSettings(
        handle_hint="near", smoothing=0.0, offset_smoothing=0.0, pixel_noise=1.0, plane_point=(3.0, 0.0, 0.0)
    )
    head_rms, handle_rms, lifted, _ = _spread_over_draws(demo, settings, 1.0)
    for rms, sigma in ((head_rms, lifted.head_sigma), (handle_rms, lifted.handle_sigma)):
        ratio = rms / sigma
        assert 0.7 < np.median(ratio) < 1.4, np.median(ratio)
        assert np.min(ratio) > 0.3 and np.max(ratio) < 2.5, (np.min(ratio), np.max(ratio))


def test_the_handle_depth_filter_removes_the_side_on_tools_tilt():
    # Side-on, the handle's depth offset is the root of a small noisy number: each frame alone tilts
    # the tool out of the plane by the noise (the lift without the offset filter measured 4.2 deg
    # here); filtering the signed offset averages the near/far flips out.
    demo = planar_demo(0.0)
    _, _, lifted, axis = _spread_over_draws(demo, LiftSettings(handle_hint="near"), 3.0, draws=20)
    assert axis < 3.9


def test_filter_diagonal_is_the_dense_maps():
    # the diagonal of the time filter's linear map (seen values -> their filtered values), read off
    # impulses filtered many at a time, equals the one read off the dense map, with gaps and ends
    rng = np.random.default_rng(3)
    for n_frames in (12, 80):
        frames = np.sort(rng.choice(n_frames, size=int(0.8 * n_frames), replace=False))
        for width in (0.5, 2.0, 8.0):
            dense = _filtered(np.eye(len(frames)), frames, n_frames, width)[frames]
            np.testing.assert_allclose(_filter_diagonal(frames, n_frames, width), np.diag(dense), atol=1e-12)


def test_cross_validation_smooths_noise_and_keeps_a_fast_motion():
    frames = np.arange(60)
    noise = np.random.default_rng(0).normal(size=(60, 2))
    assert cross_validated_width(5.0 + noise, frames, 60) >= 2.0, "a still end: a wide filter"
    fast = np.column_stack([np.sin(2 * np.pi * frames / 5), np.cos(2 * np.pi * frames / 5)])
    assert cross_validated_width(fast, frames, 60) == PIXEL_WIDTHS[0], "a turn every few frames: the narrowest"


def test_the_lift_reports_each_ends_pixel_filter():
    tracks = perturbed(project_demo(planar_demo(0.5), CAMERA), 2.0, 0.0, seed=1)
    chosen = lift_tracks(tracks, CAMERA, "spade", 24.0, LiftSettings(handle_hint="near")).pixel_smoothing
    assert all(width in PIXEL_WIDTHS for width in chosen)
    fixed = LiftSettings(handle_hint="near", smoothing=1.5)
    assert lift_tracks(tracks, CAMERA, "spade", 24.0, fixed).pixel_smoothing == (1.5, 1.5)


def test_the_lift_command_prints_the_sides_and_the_mirror(tmp_path, capsys):
    from toolimit.cli import main

    demo = planar_demo(0.5)
    write_tracks(perturbed(project_demo(demo, CAMERA), 1.0, 0.1, seed=4), tmp_path / "t.csv")
    write_camera(CAMERA, tmp_path / "c.json")
    out = tmp_path / "lifted.npz"
    argv = ["demo", "lift", str(tmp_path / "t.csv"), "--camera", str(tmp_path / "c.json"), "--tool", "spade"]
    assert main([*argv, "--fps", "24", "--handle-hint", "near", "--plane-normal", "1,0", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "handle sides: 40 frames from the hint, 0 left it; a frame on the wrong side would put" in printed
    assert "if its side is right" in printed
    record = read_lifted(out)
    assert record.arrays["side_source"].tolist() == ["hint"] * demo.n_frames
    assert np.mean(np.linalg.norm(record.demo.head - demo.head, axis=1)) < 0.02


# --- refusals --------------------------------------------------------------------------------------
def test_too_few_visible_frames():
    tracks = project_demo(planar_demo(0.5), CAMERA)
    seen = np.zeros(tracks.n_frames, dtype=bool)
    seen[:15] = True
    with pytest.raises(
        TrackError, match=r"too few visible frames: the handle is seen in 15 of 40 frames \(need at least 20"
    ):
        lift_tracks(EndpointTracks(tracks.head, tracks.handle, tracks.head_visible, seen), CAMERA, "spade", 24.0, EXACT)


def test_a_camera_that_sees_no_ground():
    demo = planar_demo(0.0).translated([0.0, 0.0, 1.5])  # every head point above the camera's height
    camera = look_at([0.0, 0.0, 1.2], [3.0, 0.0, 2.0])
    with pytest.raises(TrackError, match="camera sees no ground: only 0 of the head's 40 rays point below the horizon"):
        lift_tracks(project_demo(demo, camera), camera, "spade", 24.0, EXACT)


def test_a_mirror_ambiguity_without_a_hint():
    with pytest.raises(TrackError, match="mirror ambiguity.*--handle-hint near|far"):
        lift_tracks(project_demo(held_still(), CAMERA), CAMERA, "spade", 24.0, EXACT)


def test_a_camera_below_the_ground_and_one_looking_down():
    tracks = project_demo(planar_demo(0.5), CAMERA)
    below = look_at([0.0, 0.0, -0.2], [3.0, 0.0, 0.4])
    with pytest.raises(TrackError, match="not above the ground"):
        lift_tracks(tracks, below, "spade", 24.0, EXACT)
    with pytest.raises(TrackError, match="looking straight up or down"):
        look_at([0.0, 0.0, 3.0], [0.0, 0.0, 0.0])


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("handle_hint", "left"),
        ("tool_length", 0.0),
        ("plane_point", (1.0, 2.0)),
        ("contact_share", 0.0),
        ("smoothing", -1.0),
        ("smoothing", float("nan")),
        ("offset_smoothing", -1.0),
    ],
)
def test_settings_refuse_bad_values(field, value):
    with pytest.raises(InvalidSetting, match=field):
        LiftSettings(**{field: value})


# --- files -----------------------------------------------------------------------------------------
def test_tracks_and_camera_files_round_trip(tmp_path):
    tracks = perturbed(project_demo(planar_demo(0.5), CAMERA), 2.0, 0.1, seed=3)
    write_tracks(tracks, tmp_path / "t.csv")
    lines = (tmp_path / "t.csv").read_text().splitlines()
    assert lines[0] == ",".join(TRACKS_HEADER) == "frame,head_u,head_v,handle_u,handle_v,head_visible,handle_visible"
    assert sum(line.endswith(",0,0") for line in lines[1:]) == 4, "10 % of 40 frames dropped"
    again = read_tracks(tmp_path / "t.csv")
    np.testing.assert_allclose(again.head, tracks.head, atol=5e-4)
    assert again.handle_visible.tolist() == tracks.handle_visible.tolist()
    write_camera(CAMERA, tmp_path / "c.json")
    data = json.loads((tmp_path / "c.json").read_text())
    assert set(data) == {"width", "height", "K", "world_from_camera"}
    camera = read_camera(tmp_path / "c.json")
    np.testing.assert_allclose(camera.world_from_camera, CAMERA.world_from_camera)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("frame,head_u,head_v\n0,1,2\n", "line 1: expected the header"),
        (
            "frame,head_u,head_v,handle_u,handle_v,head_visible,handle_visible\n1,1,2,3,4,1,1\n",
            "line 2: frame: expected 0",
        ),
        (
            "frame,head_u,head_v,handle_u,handle_v,head_visible,handle_visible\n0,1,2,3,4,2,1\n",
            "line 2: head_visible: expected 0 or 1, got '2'",
        ),
        (
            "frame,head_u,head_v,handle_u,handle_v,head_visible,handle_visible\n0,1,x,3,4,1,1\n",
            "line 2: head_v: expected a number",
        ),
        (
            "frame,head_u,head_v,handle_u,handle_v,head_visible,handle_visible\n0,1,2,3,1,1\n",
            "line 2: expected 7 fields, got 6",
        ),
        ("frame,head_u,head_v,handle_u,handle_v,head_visible,handle_visible\n", "no frames"),
    ],
)
def test_bad_tracks_files(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(TrackError, match=message):
        read_tracks(path)


def test_an_unseen_end_may_have_empty_pixels(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text(",".join(TRACKS_HEADER) + "\n0,1.5,2,,,1,0\n")
    tracks = read_tracks(path)
    assert tracks.handle_visible.tolist() == [False] and np.isnan(tracks.handle).all()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"K": [[1000, 0, 640], [0, 1000, 360]]}, "K: expected a finite 3x3 matrix"),
        ({"K": [[-5, 0, 640], [0, 1000, 360], [0, 0, 1]]}, "fx, fy > 0"),
        ({"world_from_camera": np.diag([1.0, 1.0, -1.0, 1.0]).tolist()}, "reflection"),
        ({"width": 0}, "width: expected a positive whole number"),
        ({"K": [[1, "a"]]}, "nested lists of numbers"),
    ],
)
def test_bad_camera_files(tmp_path, change, message):
    data = {**CAMERA.to_json(), **change}
    path = tmp_path / "camera.json"
    path.write_text(json.dumps(data))
    with pytest.raises(TrackError, match=message):
        read_camera(path)
    del data["K"]
    path.write_text(json.dumps(data))
    with pytest.raises(TrackError, match="missing field"):
        read_camera(path)


# --- the authors' real trajectories --------------------------------------------------------------
def test_spade_video_1_seen_from_the_side_is_lifted_within_10_cm(video_demos_dir):
    """The benchmark's setting (benchmarks/video_lift.py), one noise draw."""
    truth, _, _ = load_video_trajectory(video_demos_dir / "spade_video1_aligned.npz")
    camera = side_camera(truth.head)
    tracks = perturbed(project_demo(truth, camera), 3.0, 0.05, seed=0)
    lifted = lift_tracks(tracks, camera, "spade", truth.fps, LiftSettings(handle_hint="near")).demo
    head_error = np.mean(np.linalg.norm(lifted.head - truth.head, axis=1))
    axis_error = np.degrees(np.arccos(np.clip(np.sum(lifted.axis * truth.axis, axis=1), -1, 1)))
    assert head_error < 0.10, f"mean head error {head_error:.3f} m"
    assert np.median(axis_error) < 3.0, f"median axis error {np.median(axis_error):.2f} deg"
    # Without a hint: a refusal (mirror ambiguity) or the true side, never a silently mirrored demo
    # (on this noise draw the smoothest path is now clear enough not to be ambiguous; the refusal
    # itself is tested exactly on held_still).
    try:
        unhinted = lift_tracks(tracks, camera, "spade", truth.fps, LiftSettings())
    except TrackError as error:
        assert "mirror ambiguity" in str(error)
    else:
        assert np.mean(unhinted.handle_far) < 0.5, "the handle end is on the near side of the head"


def test_the_side_camera_on_the_other_side():
    demo = planar_demo(0.5)
    one, other = side_camera(demo.head), side_camera(demo.head, other_side=True)
    centre = demo.head.mean(axis=0)
    np.testing.assert_allclose(one.centre[:2] + other.centre[:2], 2 * centre[:2], atol=1e-9)
    assert one.centre[2] == other.centre[2] == 1.2
    assert handle_side(demo, one) != handle_side(demo, other), "the near side seen from the other side is far"
