"""Reading target tool poses from files (``--poses FILE.npz``, ``DIR/aligned_demo.npz``).

Both formats hold ``tip_position`` (T, 3) metres, ``tip_quaternion_wxyz`` (T, 4) scalar first and
``fps``, in the world frame and toolimit's tool-frame convention (:mod:`toolimit.tools`). The
shared real recordings use the original code's spade tip frame instead; see
:func:`from_original_spade_tip`.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from toolimit.artifacts import load_npz
from toolimit.demos.npz_format import SPADE_TIP_TO_HANDLE
from toolimit.errors import InputError
from toolimit.trajopt.problem import PoseTargets

if TYPE_CHECKING:
    from toolimit.align.search import AlignmentResult, Candidate


def targets_from_alignment(result: AlignmentResult, candidate: Candidate | None = None) -> PoseTargets:
    """The tool poses of an alignment candidate's episode (default: the best; a timed goal's cut
    motion, :mod:`toolimit.align.episode_cut`), at the prepared demo's rate: what ``toolimit trajopt
    --alignment DIR`` reads from ``DIR/aligned_demo.npz``."""
    candidate = candidate if candidate is not None else result.best
    if candidate is None:
        raise InputError("the alignment has no candidate: no sample earned a goal reward")
    poses = result.episode_poses(candidate)
    return PoseTargets(poses.position, poses.rotation, result.demo.fps)


def load_pose_targets(path: str | os.PathLike[str]) -> PoseTargets:
    """Targets from an ``.npz`` with ``tip_position``, ``tip_quaternion_wxyz`` and ``fps``."""
    arrays = load_npz(path, required=("tip_position", "tip_quaternion_wxyz", "fps"))
    positions = np.asarray(arrays["tip_position"], dtype=float)
    quaternions = np.asarray(arrays["tip_quaternion_wxyz"], dtype=float)
    fps = float(np.asarray(arrays["fps"]).reshape(()))
    if positions.ndim != 2 or positions.shape[1] != 3:
        raise InputError(f"{path}: tip_position must have shape (T, 3), got {positions.shape}")
    try:
        return PoseTargets.from_quaternions(positions, quaternions, fps)
    except ValueError as error:
        raise InputError(f"{path}: {error}") from None


def from_original_spade_tip(targets: PoseTargets) -> PoseTargets:
    """Convert poses of the original code's spade tip frame into toolimit's tool frame.

    The origin (blade tip = tool head) is kept; z becomes the unit vector from the tip to the handle
    end (tip frame coordinates (0, 0.161, -0.369) / 0.4026); x, the blade's face normal on the
    carrying side, is the tip frame's x crossed into that axis, (0, 0.916, 0.401); y = z x x. The
    data decide the face: in ``spade_example_aligned.npz`` this x points up (z component 0.89 to
    0.99 over frames 20 to 80) all through the scoop and the carry, as a face holding sand must,
    while the tip frame's own x stays near horizontal.
    """
    z = -SPADE_TIP_TO_HANDLE / np.linalg.norm(SPADE_TIP_TO_HANDLE)  # p_handle = p_tip - R SPADE_TIP_TO_HANDLE
    x = np.cross([1.0, 0.0, 0.0], z)
    offset = np.column_stack([x, np.cross(z, x), z])
    return PoseTargets(targets.positions, targets.rotations @ offset, targets.fps)
