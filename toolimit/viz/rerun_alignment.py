"""A rerun recording of an alignment: the demonstration, its keypoints, the scene and a replay.

Entities (world frame, metres, z up): ``demo/head`` and ``demo/handle`` paths of the demonstration
as replayed (aligned by the best candidate when there is one), ``demo/keypoints`` on the head path,
``scene/params/<name>`` the candidate's element positions, then on the ``time`` timeline (seconds)
one replay: ``replay/tool`` (head-to-handle segment), ``replay/tool_x`` (the tool frame's working
direction, showing the sampled roll), ``replay/state/<key>`` the scene's snapshot arrays and
``replay/goal_reward``. ``RERUN=off`` disables it (nothing is written).

The steps before a search, as notebook 02 shows them: :func:`save_sampling_recording` (where the
sampler puts each scene element around the keypoints) and :func:`save_sample_replay_recording`
(one sample's replay, frame by frame), with the same entities.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import rerun as rr

from toolimit.align.search import AlignmentResult
from toolimit.demos import ToolDemo
from toolimit.scenes.base import Scene, SceneParams
from toolimit.scenes.registry import make_scene
from toolimit.scenes.replay import replay
from toolimit.viz.rerun_file import recording_file, save_recording

HEAD_COLOUR = (230, 120, 30)
HANDLE_COLOUR = (60, 140, 230)
KEYPOINT_COLOUR = (220, 30, 60)
ELEMENT_COLOUR = (40, 170, 80)
STATE_COLOUR = (150, 150, 150)


def save_alignment_recording(result: AlignmentResult, path: str | Path, scene: Scene | None = None) -> Path | None:
    """Write the recording of ``result`` to ``path`` (.rrd); None when rerun is disabled.

    ``scene`` replays the best candidate (default: a new scene from the registry): one instance
    reset from the candidate's own generator right after its draw, which is exactly the search's
    first run of that sample when it screened with one run (the default).
    """
    with recording_file(path, "toolimit_alignment") as recording:
        if recording is None:
            return None
        _log_alignment(recording, result, scene)
    return Path(path)


def _log_alignment(recording: rr.RecordingStream, result: AlignmentResult, scene: Scene | None) -> None:
    best = result.best
    if best is None:
        demo, poses = result.demo, None
    else:
        demo, _, poses = result.aligned_motion(best)
    recording.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    recording.log("demo/head", rr.LineStrips3D([demo.head], colors=HEAD_COLOUR), static=True)
    recording.log("demo/handle", rr.LineStrips3D([demo.handle], colors=HANDLE_COLOUR), static=True)
    recording.log(
        "demo/keypoints",
        rr.Points3D(
            demo.head[result.keypoints],
            radii=0.015,
            colors=KEYPOINT_COLOUR,
            labels=[f"frame {k}" for k in result.keypoints],
        ),
        static=True,
    )
    recording.log(
        "search",
        rr.TextDocument(
            f"{result.tool} / {result.world}: {len(result.candidates)} candidate(s) in "
            f"{result.samples_tried} samples ({result.samples_rejected} rejected), "
            f"seed {result.seed}, {result.wall_time_s:.1f} s"
        ),
        static=True,
    )
    if best is None or poses is None:
        return
    for name, value in best.sample.params.items():
        value = np.asarray(value, dtype=float)
        if value.shape == (3,):
            recording.log(
                f"scene/params/{name}",
                rr.Points3D([value], radii=0.03, colors=ELEMENT_COLOUR, labels=[name]),
                static=True,
            )
    scene = scene or make_scene(result.tool, result.world)

    def log_step(frame: int, stepped: Scene) -> None:
        position, rotation = poses.position[frame], poses.rotation[frame]
        recording.set_time("time", duration=frame * stepped.control_dt)
        recording.log("replay/tool", rr.LineStrips3D([[demo.head[frame], demo.handle[frame]]], radii=0.01))
        recording.log("replay/tool_x", rr.Arrows3D(vectors=[0.1 * rotation[:, 0]], origins=[position]))
        recording.log("replay/goal_reward", rr.Scalars(float(np.asarray(stepped.goal_reward())[0])))
        _log_snapshot(recording, stepped.snapshot())

    replay(scene, best.sample.params, result.replay_generator(best, scene.parameters), poses, on_step=log_step)


def _log_snapshot(recording: rr.RecordingStream, snapshot: dict[str, np.ndarray]) -> None:
    """Segments (M, 2, 3) as lines, points (..., 3) as points, scalars as plots.

    Sizes and orientations (keys ending in ``extents`` or ``rotation``) and non-numeric arrays are
    not drawn: they are (..., 3) arrays that are not positions.
    """
    for key, value in snapshot.items():
        value = np.asarray(value)
        if value.dtype.kind not in "fiub" or key.endswith(("extents", "rotation")):
            continue
        if value.ndim == 3 and value.shape[1:] == (2, 3):
            recording.log(f"replay/state/{key}", rr.LineStrips3D(value, radii=0.005, colors=STATE_COLOUR))
        elif value.ndim >= 1 and value.shape[-1] == 3:
            recording.log(f"replay/state/{key}", rr.Points3D(value.reshape(-1, 3), radii=0.01, colors=STATE_COLOUR))
        elif value.size == 1:
            recording.log(f"replay/state/{key}", rr.Scalars(float(value.reshape(()))))


def save_sampling_recording(
    path: str | os.PathLike[str],
    demo: ToolDemo,
    keypoints: np.ndarray,
    samples: Mapping[str, np.ndarray],
    show_inline: bool = False,
) -> Path | None:
    """The sampler's draws: ``demo``'s head path, its ``keypoints`` (K,) frame indices, and every
    drawn position of each scene element (name -> (N, 3), world frame, m) under
    ``samples/<name>``; None when rerun is disabled (``show_inline``: :func:`save_recording`)."""
    frames = np.asarray(keypoints, dtype=int)

    def log(recording: rr.RecordingStream) -> None:
        recording.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        recording.log("demo/head", rr.LineStrips3D([demo.head], colors=HEAD_COLOUR), static=True)
        recording.log(
            "demo/keypoints",
            rr.Points3D(demo.head[frames], radii=0.015, colors=KEYPOINT_COLOUR, labels=[f"frame {k}" for k in frames]),
            static=True,
        )
        for name, positions in samples.items():
            recording.log(f"samples/{name}", rr.Points3D(np.asarray(positions), radii=0.006), static=True)

    return save_recording(path, log, "toolimit_sampling", show_inline=show_inline)


def save_sample_replay_recording(
    path: str | os.PathLike[str],
    aligned: ToolDemo,
    params: SceneParams,
    snapshots: Sequence[Mapping[str, np.ndarray]],
    control_dt: float,
    show_inline: bool = False,
) -> Path | None:
    """One sample replayed: its element positions under ``scene/params/<name>``, then per control
    step (``control_dt`` s) the tool segment of ``aligned`` (the motion as replayed, world frame,
    m) and the scene's ``snapshots``; None when rerun is disabled."""
    if len(snapshots) > len(aligned.head):
        raise ValueError(f"{len(snapshots)} snapshots for a motion of {len(aligned.head)} frames")

    def log(recording: rr.RecordingStream) -> None:
        recording.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        for name, value in params.items():
            if np.ndim(value) == 1:
                recording.log(
                    f"scene/params/{name}",
                    rr.Points3D([value], radii=0.03, colors=ELEMENT_COLOUR, labels=[name]),
                    static=True,
                )
        for frame, snapshot in enumerate(snapshots):
            recording.set_time("time", duration=frame * control_dt)
            recording.log("replay/tool", rr.LineStrips3D([[aligned.head[frame], aligned.handle[frame]]], radii=0.01))
            _log_snapshot(recording, dict(snapshot))

    return save_recording(path, log, "toolimit_sample_replay", show_inline=show_inline)
