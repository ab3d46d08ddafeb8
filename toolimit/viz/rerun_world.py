"""A rerun recording (.rrd) of a 3D world replay: boxes, spheres and the tool over time.

The same frames as :mod:`toolimit.viz.meshcat_views` (scene snapshots of instance 0, one per
control step), drawn from the same :mod:`toolimit.viz.world_elements`. Entities (world frame,
metres, z up): ``world/<group>`` one ``Boxes3D`` or ``Points3D`` batch per element group
(``world/board``, ``world/nail``, ``world/stalks``, ``world/sand``, ...), ``world/tool`` a
``Transform3D`` of the tool frame with the tool's boxes and capsules (from
:mod:`toolimit.scenes.spatial.tool_geometry`) logged once in that frame under
``world/tool/shapes``, and ``world/tool_path`` the head point's path so far. Timeline ``time``
(seconds). ``RERUN=off`` disables it: nothing is written and the function returns None.
"""

from __future__ import annotations

import os
from collections import defaultdict
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import rerun as rr
from scipy.spatial.transform import Rotation

from toolimit.scenes.base import CONTROL_FPS
from toolimit.scenes.spatial.tool_geometry import tool_shapes
from toolimit.viz.rerun_file import recording_file
from toolimit.viz.world_elements import Element, world_elements


def _rgba8(colour: Sequence[float] | np.ndarray) -> list[int]:
    return [int(round(255 * c)) for c in colour]


def _log_elements(recording: rr.RecordingStream, elements: list[Element]) -> None:
    """One Boxes3D / Points3D batch per group of elements."""
    groups: dict[str, list[Element]] = defaultdict(list)
    for element in elements:
        groups[element.group].append(element)
    for group, members in groups.items():
        boxes = [e for e in members if e.shape == "box"]
        spheres = [e for e in members if e.shape == "sphere"]
        if boxes:
            recording.log(
                f"world/{group}",
                rr.Boxes3D(
                    centers=[e.transform[:3, 3] for e in boxes],
                    half_sizes=[e.size for e in boxes],
                    quaternions=Rotation.from_matrix([e.transform[:3, :3] for e in boxes]).as_quat(),  # x, y, z, w
                    colors=[_rgba8(e.colour) for e in boxes],
                    fill_mode="solid",
                ),
            )
        if spheres:
            recording.log(
                f"world/{group}" + ("/spheres" if boxes else ""),
                rr.Points3D(
                    [e.transform[:3, 3] for e in spheres],
                    radii=[float(e.size[0]) for e in spheres],
                    colors=[_rgba8(e.colour) for e in spheres],
                ),
            )


def _log_tool_shapes(recording: rr.RecordingStream, tool: str) -> None:
    """The tool's boxes and capsules in the tool frame (static, under the moving ``world/tool``)."""
    shapes = tool_shapes(tool)
    recording.log(
        "world/tool/shapes/boxes",
        rr.Boxes3D(
            centers=shapes.box_centers,
            half_sizes=shapes.box_half_extents,
            quaternions=Rotation.from_matrix(shapes.box_rotations).as_quat(),
            colors=[_rgba8(b.colour) for b in shapes.boxes],
            fill_mode="solid",
        ),
        static=True,
    )
    if len(shapes.capsules):
        axes = shapes.capsule_ends - shapes.capsule_starts
        recording.log(
            "world/tool/shapes/capsules",
            rr.Capsules3D(
                lengths=np.linalg.norm(axes, axis=1),
                radii=shapes.capsule_radii,
                translations=shapes.capsule_starts,  # rerun capsules run along +z from the translation
                quaternions=Rotation.from_matrix([c.rotation for c in shapes.capsules]).as_quat(),
                colors=[_rgba8(c.colour) for c in shapes.capsules],
            ),
            static=True,
        )


def save_replay_recording(
    path: str | os.PathLike[str],
    frames: Sequence[Mapping[str, np.ndarray]],
    tool: str,
    fps: float = CONTROL_FPS,
) -> Path | None:
    """Write the replay ``frames`` of the 3D ``tool`` world to ``path`` (.rrd) atomically.

    Returns the path, or None when rerun is disabled (``RERUN=off``).
    """
    if len(frames) == 0:
        raise ValueError("a replay needs at least one frame")
    with recording_file(path, "toolimit_world_replay") as recording:
        if recording is None:
            return None
        recording.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        _log_tool_shapes(recording, tool)
        head_path = []
        for index, snapshot in enumerate(frames):
            recording.set_time("time", duration=index / fps)
            _log_elements(recording, world_elements(tool, snapshot))
            position, rotation = snapshot["tool_position"], snapshot["tool_rotation"]
            if np.all(np.isfinite(position)) and np.all(np.isfinite(rotation)):
                recording.log("world/tool", rr.Transform3D(translation=position, mat3x3=rotation))
                head_path.append(np.asarray(position, dtype=float))
                recording.log("world/tool_path", rr.LineStrips3D([np.array(head_path)], colors=[230, 120, 30]))
    return Path(path)
