"""Demonstrations from the video motion estimator the paper used.

Li et al. 2019, "Estimating 3D Motion and Forces of Person-Object Interactions from Monocular
Video", writes one Python pickle per video. The keys read here (layout as in the paper's code,
``kzorina/learning-from-video``, ``method/I_alignment/human_demonstrations/load_mfv_outputs.py``):

* ``fps``: frame rate, Hz;
* ``keypoint_3d_positions_object``: (6, nf) matrix; rows 0-2 the handle end, rows 3-5 the tool
  head, camera frame, metres;
* ``joint_3d_positions_person``: (72, nf) matrix = 24 joints x (x, y, z), camera frame, metres.
  The estimator's 24-joint rig is *not* SMPL's joint order: its joint table
  (``mfv_person_joints.txt``) puts ``l_toes`` at 4 and ``r_toes`` at 8 (SMPL would have the feet
  at 10 and 11); we follow the estimator's table, which is what the paper's code does;
* optional ``config_object`` (nf, 7) and the person configuration, contacts and forces, which a
  tool demonstration does not need.

The camera frame has x right, y down, z forward (away from the camera). :func:`canonical_demo`
turns it into the world frame the way the paper's code does (``load_tool_demonstration_extracted_
from_video`` with ``offset_by_plane=True``): subtract the median over frames of the mid-point of the
two toes, then rotate by -90 degrees about x, so ``(x, y, z)_world = (x, z, -y)_camera``: z up
(the camera's y pointed down), y forward, x unchanged.

Security: unpickling can run arbitrary code. :func:`read_motion_estimate` uses an unpickler that
only builds numpy arrays, matrices, scalars and plain Python containers and refuses every other
class, but still: only load files from sources you trust.
"""

from __future__ import annotations

import io
import pickle
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from toolimit.demos.tool_demo import ToolDemo, finite_frames, frame_rate_problem
from toolimit.errors import DemoError
from toolimit.tools import tool_spec

#: Indices of the left and right toes in the estimator's 24-joint rig (its ``mfv_person_joints.txt``).
LEFT_TOES, RIGHT_TOES = 4, 8
N_PERSON_JOINTS = 24

#: Camera frame (x right, y down, z forward) -> world frame (z up): rotation by -90 deg about x.
CAMERA_TO_WORLD = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

#: The only classes the unpickler may build (module, name); old numpy/Python 2 spellings included.
_ALLOWED_CLASSES = {
    ("numpy", "ndarray"),
    ("numpy", "dtype"),
    ("numpy", "matrix"),
    ("numpy.matrixlib.defmatrix", "matrix"),
    ("numpy._core.multiarray", "_reconstruct"),
    ("numpy._core.multiarray", "scalar"),
    ("numpy._core.numeric", "_frombuffer"),
    ("copyreg", "_reconstructor"),
    ("builtins", "object"),
    ("_codecs", "encode"),
}


class _ArraysOnlyUnpickler(pickle.Unpickler):
    """Builds numpy arrays and plain containers; any other class is refused before it is imported."""

    def find_class(self, module: str, name: str) -> Any:
        module = {
            "numpy.core.multiarray": "numpy._core.multiarray",
            "numpy.core.numeric": "numpy._core.numeric",
            "copy_reg": "copyreg",
            "__builtin__": "builtins",
        }.get(module, module)
        if (module, name) not in _ALLOWED_CLASSES:
            raise pickle.UnpicklingError(f"refusing to load {module}.{name} (only numpy arrays are allowed)")
        return super().find_class(module, name)


@dataclass(frozen=True)
class MotionEstimate:
    """What a tool demonstration needs from the estimator's output, in the *camera* frame.

    Attributes:
        fps: frame rate, Hz.
        handle: (T, 3) handle end, camera frame (x right, y down, z forward), metres.
        head: (T, 3) tool head, camera frame, metres.
        person_joints: (T, 24, 3) person joints (estimator's rig), camera frame, metres.
        source: the file read.
    """

    fps: float
    handle: np.ndarray
    head: np.ndarray
    person_joints: np.ndarray
    source: str = ""

    @property
    def toes_centre(self) -> np.ndarray:
        """(3,) median over frames of the mid-point of the two toes, camera frame, metres."""
        toes = self.person_joints[:, [LEFT_TOES, RIGHT_TOES], :]
        return np.median(toes.mean(axis=1), axis=0)


def read_motion_estimate(path: str | Path) -> MotionEstimate:
    """Read and check an estimator pickle. Only load files you trust (see the module notes)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"motion estimator file not found: {path}")
    try:
        data = _ArraysOnlyUnpickler(io.BytesIO(path.read_bytes()), encoding="latin1").load()
    except (pickle.UnpicklingError, EOFError, ValueError, TypeError, AttributeError, ImportError) as error:
        raise DemoError(f"{path}: not a readable motion estimator pickle ({error})") from None
    if not isinstance(data, dict):
        raise DemoError(f"{path}: expected a dict of arrays, got {type(data).__name__}")
    for key in ("fps", "keypoint_3d_positions_object", "joint_3d_positions_person"):
        if key not in data:
            raise DemoError(f"{path}: missing key {key!r} (keys: {sorted(map(str, data))})")
    fps = np.asarray(data["fps"])
    if fps.size != 1 or not np.issubdtype(fps.dtype, np.number):
        raise DemoError(f"{path}: key 'fps' must be a number, got {data['fps']!r}")
    if problem := frame_rate_problem(fps.item()):
        raise DemoError(f"{path}: key 'fps' {problem}")
    keypoints = _matrix(path, data, "keypoint_3d_positions_object", 6)
    joints = _matrix(path, data, "joint_3d_positions_person", 3 * N_PERSON_JOINTS)
    if keypoints.shape[1] != joints.shape[1]:
        raise DemoError(
            f"{path}: 'keypoint_3d_positions_object' has {keypoints.shape[1]} frames but "
            f"'joint_3d_positions_person' has {joints.shape[1]}"
        )
    return MotionEstimate(
        fps=float(fps.item()),
        handle=keypoints[0:3].T.copy(),
        head=keypoints[3:6].T.copy(),
        person_joints=joints.T.reshape(-1, N_PERSON_JOINTS, 3),
        source=str(path),
    )


def _matrix(path: Path, data: dict, key: str, rows: int) -> np.ndarray:
    value = np.asarray(data[key])  # np.matrix -> ndarray
    if value.ndim != 2 or value.shape[0] != rows:
        raise DemoError(f"{path}: key {key!r} must have shape ({rows}, nf), got {value.shape}")
    return finite_frames(path, key, value, frame_axis=1)


def canonical_demo(estimate: MotionEstimate, tool: str, rescale: str = "tool") -> ToolDemo:
    """The estimate in the world frame (z up, origin at the median toes mid-point), as a ToolDemo.

    Args:
        estimate: camera-frame estimate.
        tool: tool name; its ``tool_spec(tool).length`` (metres) is imposed.
        rescale: ``"tool"`` (the paper's code): the head path is kept and each frame's handle end
            is put on the estimated tool axis at the tool's length. ``"motion"``: the whole motion
            is first scaled about the toes' centre by tool length / median estimated length (for
            an estimate whose global scale is off, monocular depth being ambiguous), then the
            length is imposed the same way.
    """
    length = tool_spec(tool).length
    if rescale not in ("tool", "motion"):
        raise DemoError(f"rescale: expected 'tool' or 'motion', got {rescale!r}")
    centre = estimate.toes_centre
    head = (estimate.head - centre) @ CAMERA_TO_WORLD.T
    handle = (estimate.handle - centre) @ CAMERA_TO_WORLD.T
    estimated = np.linalg.norm(handle - head, axis=1)
    if np.min(estimated) < 1e-6:
        frame = int(np.argmin(estimated))
        raise DemoError(f"{estimate.source}: head and handle end coincide at frame {frame} (zero-length tool)")
    if rescale == "motion":
        factor = length / float(np.median(estimated))
        head, handle = head * factor, handle * factor
        estimated = estimated * factor
    handle = head + (handle - head) * (length / estimated)[:, None]
    return ToolDemo(head, handle, estimate.fps, tool, source=f"{estimate.source} (motion estimator, rescale={rescale})")


def load_motion_estimate_demo(path: str | Path, tool: str, rescale: str = "tool") -> ToolDemo:
    """Read an estimator pickle and canonicalise it (see :func:`canonical_demo`)."""
    try:
        return canonical_demo(read_motion_estimate(path), tool, rescale=rescale)
    except DemoError as error:
        message = str(error)
        raise DemoError(message if message.startswith(str(path)) else f"{path}: {message}") from None
