"""rerun recording of demonstrations: the tool speed with its velocity keypoints, and the paths.

Entities, one set per named demonstration: ``speed/<name>`` (tool speed, m/s; timeline ``time``,
s from the first frame) and ``speed/<name>_keypoints`` (:func:`toolimit.align.keypoints.velocity_keypoints`);
in the world frame (m, z up) ``world/<name>/head`` and ``world/<name>/handle`` (the paths) and
``world/<name>/keypoints`` (the head at the keypoints, labelled by frame).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

import rerun as rr

from toolimit.align.keypoints import velocity_keypoints
from toolimit.demos import ToolDemo
from toolimit.viz.rerun_file import save_recording

#: RGB of successive demonstrations.
COLOURS = ((200, 60, 60), (40, 120, 220), (0, 158, 115), (230, 159, 0))


def save_demo_recording(
    path: str | os.PathLike[str], demos: Mapping[str, ToolDemo], show_inline: bool = False
) -> Path | None:
    """Write ``demos`` (name -> demonstration) to ``path`` (.rrd) and return it; None when rerun is
    disabled. ``show_inline`` also shows the recording in a notebook (:func:`save_recording`)."""
    if not demos:
        raise ValueError("a recording needs at least one demonstration")

    def log(recording: rr.RecordingStream) -> None:
        recording.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        for index, (name, demo) in enumerate(demos.items()):
            colour = COLOURS[index % len(COLOURS)]
            speed, frames = demo.speed(), velocity_keypoints(demo)
            recording.log(f"speed/{name}", rr.SeriesLines(colors=colour, names=f"{name} speed (m/s)"), static=True)
            recording.send_columns(
                f"speed/{name}",
                indexes=[rr.TimeColumn("time", duration=demo.times)],
                columns=rr.Scalars.columns(scalars=speed),
            )
            recording.log(
                f"speed/{name}_keypoints", rr.SeriesPoints(colors=colour, markers="circle", marker_sizes=6), static=True
            )
            recording.send_columns(
                f"speed/{name}_keypoints",
                indexes=[rr.TimeColumn("time", duration=demo.times[frames])],
                columns=rr.Scalars.columns(scalars=speed[frames]),
            )
            recording.log(f"world/{name}/head", rr.LineStrips3D([demo.head], colors=colour), static=True)
            recording.log(
                f"world/{name}/handle", rr.LineStrips3D([demo.handle], colors=colour, radii=0.003), static=True
            )
            recording.log(
                f"world/{name}/keypoints",
                rr.Points3D(demo.head[frames], radii=0.015, colors=colour, labels=[f"frame {k}" for k in frames]),
                static=True,
            )

    return save_recording(path, log, "toolimit_demonstration", show_inline=show_inline)
