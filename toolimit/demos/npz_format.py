"""Reading and writing demonstration files.

Three kinds of file become a :class:`ToolDemo`:

* the project's own ``.npz``: keys ``head`` (T, 3), ``handle`` (T, 3) (world frame, metres),
  ``fps`` (scalar, Hz), ``tool`` (str); other keys are allowed and ignored by :func:`load_demo`;
* the real aligned trajectories of the paper's authors (``../shared/data/video_demos`` beside the checkout): keys
  ``tip_position`` (T, 3) metres and ``tip_quaternion_wxyz`` (T, 4) scalar first, ``fps``, plus
  scene parameters; the pose of the tool *tip frame* becomes head and handle points (see
  :func:`tip_frame_handle`);
* the pickle written by the video motion estimator (``.pkl``), see
  :mod:`toolimit.demos.motion_estimator`.

Every problem is a :class:`DemoError` (or ``FileNotFoundError``) whose message names the file, the
key and what is wrong.
"""

from __future__ import annotations

import io
import os
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from toolimit.artifacts import atomic_path, load_npz
from toolimit.demos.tool_demo import ToolDemo, finite_frames, frame_rate_problem
from toolimit.errors import DemoError
from toolimit.tools import TOOLS, ToolPose, tool_spec

#: Spade tip frame -> handle end: ``p_handle = p_tip - R_tip @ SPADE_TIP_TO_HANDLE`` (metres).
#: The original tool model puts the tip at (0, 0.045, 0.40) m from the handle mount, rotated
#: -30 degrees about x (README of the shared data); its norm is 0.4026 m.
SPADE_TIP_TO_HANDLE = np.array([0.0, -0.161, 0.369])

#: Suffixes read as motion-estimator pickles.
PICKLE_SUFFIXES = (".pkl", ".pickle")

#: Fixed timestamp of every member of a written ``.npz`` so that the same arrays give the same bytes.
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


# --- writing -----------------------------------------------------------------------------------
def save_demo(demo: ToolDemo, path: str | os.PathLike[str], **extra_arrays: Any) -> None:
    """Write ``demo`` to ``path`` in the project's ``.npz`` format, atomically and byte-reproducibly.

    Keys: ``head``, ``handle`` (T, 3) float64 metres (world frame), ``fps`` (float64 scalar),
    ``tool`` and ``source`` (str scalars), plus ``extra_arrays`` (any name but those five). The zip
    members carry a fixed timestamp, so the same demo gives the same file bytes.
    """
    reserved = {"head", "handle", "fps", "tool", "source"} & set(extra_arrays)
    if reserved:
        raise DemoError(f"{path}: extra arrays may not reuse the demo keys {sorted(reserved)}")
    arrays: dict[str, np.ndarray] = {
        "head": np.asarray(demo.head, dtype=np.float64),
        "handle": np.asarray(demo.handle, dtype=np.float64),
        "fps": np.asarray(demo.fps, dtype=np.float64),
        "tool": np.asarray(demo.tool),
        "source": np.asarray(demo.source),
    }
    for name, value in extra_arrays.items():
        array = np.asarray(value)
        if array.dtype == object:
            raise DemoError(f"{path}: extra array {name!r} has dtype object (cannot be stored without pickle)")
        arrays[name] = array
    with atomic_path(path) as tmp:
        _write_npz_deterministic(tmp, arrays)


def _write_npz_deterministic(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """An uncompressed ``.npz`` (what ``numpy.savez`` writes) with fixed member timestamps."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED) as archive:
        for name, array in arrays.items():
            buffer = io.BytesIO()
            np.lib.format.write_array(buffer, array, allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_DATE)
            info.external_attr = 0o644 << 16
            archive.writestr(info, buffer.getvalue())


# --- reading -----------------------------------------------------------------------------------
def load_demo(path: str | os.PathLike[str], tool: str | None = None, fps: float | None = None) -> ToolDemo:
    """Read a demonstration file (project ``.npz``, real aligned ``.npz`` or estimator ``.pkl``).

    Args:
        path: the file.
        tool: tool name; needed for files that do not store it (the real trajectories and the
            estimator pickles) unless the file name starts with a known tool name
            (``spade_video1_aligned.npz`` -> spade). For a project file it must match the stored one.
        fps: frame rate (Hz) for files without an ``fps`` key (``spade_example_poses.npz``).

    Raises:
        FileNotFoundError: no such file.
        DemoError: unknown file type, missing keys, wrong shapes, NaN, too few frames, zero-length
            tool; the message names the file and the key.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"demonstration file not found: {path}")
    if path.suffix.lower() in PICKLE_SUFFIXES:
        from toolimit.demos.motion_estimator import load_motion_estimate_demo

        return load_motion_estimate_demo(path, tool=_tool_name(path, tool))
    if path.suffix.lower() != ".npz":
        raise DemoError(
            f"{path}: unknown demonstration file type {path.suffix!r} "
            f"(expected .npz, or {' / '.join(PICKLE_SUFFIXES)} from the video motion estimator)"
        )
    arrays = load_npz(path, DemoError)
    if "head" in arrays or "handle" in arrays:
        return _project_demo(path, arrays, tool)
    if "tip_position" in arrays:
        demo, _, _ = _video_trajectory(path, arrays, tool, fps)
        return demo
    raise DemoError(
        f"{path}: not a demonstration: keys {sorted(arrays)}; expected 'head', 'handle', 'fps', "
        "'tool' (project format) or 'tip_position', 'tip_quaternion_wxyz', 'fps' (aligned video trajectory)"
    )


def load_video_trajectory(
    path: str | os.PathLike[str], tool: str | None = None, fps: float | None = None
) -> tuple[ToolDemo, ToolPose, dict[str, np.ndarray]]:
    """A real aligned trajectory: the demo, the full tip-frame poses and the scene parameters.

    Returns:
        tuple: ``(demo, tip, params)``. ``demo``: head and handle points (world frame of the
            aligned scene, metres). ``tip``: ``ToolPose`` of the file's *tip frame* (position
            (T, 3) metres, rotation (T, 3, 3)): the original code's frame, not this project's tool
            frame. ``params``: every other array of the file (e.g. ``goal_box_position`` (3,),
            ``nail_position`` (3,), ``sand_buffer_yaw``), plus ``handle_axis_in_tip_frame`` (3,),
            the tip-frame direction used to place the handle end.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"trajectory file not found: {path}")
    if path.suffix.lower() != ".npz":
        raise DemoError(f"{path}: expected an .npz aligned trajectory, got suffix {path.suffix!r}")
    arrays = load_npz(path, DemoError)
    if "tip_position" not in arrays:
        raise DemoError(f"{path}: missing key 'tip_position' (keys: {sorted(arrays)})")
    return _video_trajectory(path, arrays, tool, fps)


#: The authors' aligned files' scene parameter names and the scenes' names for them.
ORIGINAL_PARAMETER_NAMES = {
    "sand_buffer_position": "sand_position",
    "sand_buffer_yaw": "sand_yaw",
    "goal_box_position": "goal_position",
    "nail_position": "nail_position",
}


def original_scene_params(arrays: dict[str, np.ndarray]) -> dict[str, np.ndarray | float]:
    """The scene parameters among an authors' aligned file's ``arrays``, under the scenes' names
    (:data:`ORIGINAL_PARAMETER_NAMES`): positions (3,) m, world frame; yaws float rad."""
    return {
        ORIGINAL_PARAMETER_NAMES[key]: float(value) if np.ndim(value) == 0 else np.asarray(value, dtype=float)
        for key, value in arrays.items()
        if key in ORIGINAL_PARAMETER_NAMES
    }


def _tool_name(path: Path, tool: str | None) -> str:
    """The explicit ``tool``, else the known tool name the file name starts with."""
    if tool is not None:
        try:
            tool_spec(tool)
        except ValueError as error:
            raise DemoError(f"{path}: {error}") from None
        return tool
    stem = path.stem.lower()
    for name in TOOLS:
        if stem.startswith(name):
            return name
    raise DemoError(f"{path}: the file does not say which tool it shows; pass tool= (one of {', '.join(TOOLS)})")


def _points(path: Path, arrays: dict[str, np.ndarray], key: str, width: int = 3) -> np.ndarray:
    if key not in arrays:
        raise DemoError(f"{path}: missing key {key!r} (keys: {sorted(arrays)})")
    value = arrays[key]
    if value.ndim != 2 or value.shape[1] != width:
        raise DemoError(f"{path}: key {key!r} must have shape (T, {width}), got {value.shape}")
    return finite_frames(path, key, value, frame_axis=0)


def _fps(path: Path, arrays: dict[str, np.ndarray], fps: float | None) -> float:
    if "fps" not in arrays:
        if fps is None:
            raise DemoError(f"{path}: missing key 'fps' (keys: {sorted(arrays)}); pass fps= to say the frame rate")
        value = fps
    else:
        stored = arrays["fps"]
        if stored.shape != () or not np.issubdtype(stored.dtype, np.number):
            raise DemoError(
                f"{path}: key 'fps' must be a numeric scalar, got shape {stored.shape} dtype {stored.dtype}"
            )
        value = float(stored)
        if fps is not None and not np.isclose(fps, value):
            raise DemoError(f"{path}: fps={fps} was asked but the file stores fps={value}")
    if problem := frame_rate_problem(value):
        raise DemoError(f"{path}: key 'fps' {problem}")
    return float(value)


def _string(path: Path, arrays: dict[str, np.ndarray], key: str) -> str:
    value = arrays[key]
    if value.shape != () or value.dtype.kind != "U":
        raise DemoError(f"{path}: key {key!r} must be a string scalar, got shape {value.shape} dtype {value.dtype}")
    return str(value)


def _project_demo(path: Path, arrays: dict[str, np.ndarray], tool: str | None) -> ToolDemo:
    head = _points(path, arrays, "head")
    handle = _points(path, arrays, "handle")
    if "tool" not in arrays:
        raise DemoError(f"{path}: missing key 'tool' (keys: {sorted(arrays)})")
    stored_tool = _string(path, arrays, "tool")
    if tool is not None and tool != stored_tool:
        raise DemoError(f"{path}: tool={tool!r} was asked but the file shows a {stored_tool!r}")
    source = _string(path, arrays, "source") if "source" in arrays else ""
    fps = _fps(path, arrays, None)
    try:
        return ToolDemo(head, handle, fps, stored_tool, source=source or str(path))
    except DemoError as error:
        raise DemoError(f"{path}: {error}") from None


def _video_trajectory(
    path: Path, arrays: dict[str, np.ndarray], tool: str | None, fps: float | None
) -> tuple[ToolDemo, ToolPose, dict[str, np.ndarray]]:
    name = _tool_name(path, tool)
    position = _points(path, arrays, "tip_position")
    quaternion = _points(path, arrays, "tip_quaternion_wxyz", width=4)
    if quaternion.shape[0] != position.shape[0]:
        raise DemoError(
            f"{path}: 'tip_quaternion_wxyz' has {quaternion.shape[0]} rows but 'tip_position' has {position.shape[0]}"
        )
    norms = np.linalg.norm(quaternion, axis=1)
    if np.any(np.abs(norms - 1.0) > 1e-3):
        frame = int(np.argmax(np.abs(norms - 1.0)))
        raise DemoError(f"{path}: 'tip_quaternion_wxyz' row {frame} is not a unit quaternion (norm {norms[frame]:.4f})")
    rate = _fps(path, arrays, fps)
    rotation = Rotation.from_quat(quaternion, scalar_first=True).as_matrix()
    tip_to_handle = tip_frame_handle(name, position, rotation, rate)
    handle = position + np.einsum("tij,j->ti", rotation, tip_to_handle)
    params = {k: v for k, v in arrays.items() if k not in ("tip_position", "tip_quaternion_wxyz", "fps")}
    params["handle_axis_in_tip_frame"] = tip_to_handle / np.linalg.norm(tip_to_handle)
    try:
        demo = ToolDemo(position, handle, rate, name, source=f"{path} (aligned video trajectory)")
    except DemoError as error:
        raise DemoError(f"{path}: {error}") from None
    return demo, ToolPose(position=position, rotation=rotation), params


def tip_frame_handle(tool: str, position: np.ndarray, rotation: np.ndarray, fps: float) -> np.ndarray:
    """(3,) vector from the tip to the handle end, in the tip frame of a real trajectory (metres).

    * spade: ``-SPADE_TIP_TO_HANDLE`` from the original tool model (0.4026 m long).
    * hammer (the original frame convention is undocumented): the tip-frame axis (+-x, +-y, +-z)
      *least aligned with the head's velocity*, weighted by squared speed, at the hammer's length
      ``tool_spec("hammer").length``. Why: in a swing the head moves across the handle (the
      handle turns about the wrist at its end), so the handle is the body axis the fast motion is
      perpendicular to. Its sign is the side the head's normal (centripetal) acceleration points
      to, since the arc's centre, the wrist, is at the handle end. One axis for the whole file:
      it is a property of the frame convention, not of a frame. (The public ``HammerTool`` model
      of kzorina/pyphysx_envs hangs the handle along its body's -z, but in
      ``hammer_video1_aligned.npz`` the head moves more along +-z (speed^2-weighted mean |cos|
      0.53) than along +-y (0.43), so that file's frame is not evidently that body frame; the
      rule above picks +y there.)
    * other tools: their tip frames are this project's tool frame, so +z at ``tool_spec`` length.

    ``position`` (T, 3) metres and ``rotation`` (T, 3, 3) are the tip frame's poses, ``fps`` Hz.
    """
    if tool == "spade":
        return -SPADE_TIP_TO_HANDLE
    length = tool_spec(tool).length
    if tool != "hammer":
        return np.array([0.0, 0.0, length])
    velocity = np.gradient(position, 1.0 / fps, axis=0)
    acceleration = np.gradient(velocity, 1.0 / fps, axis=0)
    speed = np.linalg.norm(velocity, axis=1)
    weight = speed**2
    moving = speed > 1e-9
    direction = np.zeros_like(velocity)
    direction[moving] = velocity[moving] / speed[moving, None]
    # Acceleration across the motion (towards the centre of the arc).
    normal = acceleration - np.sum(acceleration * direction, axis=1, keepdims=True) * direction
    alignment = [np.sum(weight * np.abs(np.sum(rotation[:, :, k] * direction, axis=1))) for k in range(3)]
    k = int(np.argmin(alignment))
    sign = 1.0 if np.sum(weight * np.sum(rotation[:, :, k] * normal, axis=1)) >= 0 else -1.0
    vector = np.zeros(3)
    vector[k] = sign * length
    return vector
