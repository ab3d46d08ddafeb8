"""The alignment's files: ``alignment.json`` (the search's record) and ``aligned_demo.npz``.

Formats are the project's shared ones (docs/tutorial.md#ii-alignment-runsspade_planaralignment): the aligned demo is a
demo file (head, handle, fps, tool) of the best candidate's motion as the tool alone reached it
(within the tool speed limit, :func:`toolimit.scenes.replay.speed_limited`) in the scene's world
frame plus the same motion's tool-frame poses (``tip_position`` (T, 3) m, ``tip_quaternion_wxyz``
(T, 4) scalar first), its per-frame roll (T,) rad, the scene's world and every scene parameter as
``param_<name>``.
``candidates.npz`` stacks the same poses and parameters for all K kept candidates (axis 0), so that
trajectory optimisation can select the candidate a robot reproduces best.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from toolimit.align.search import AlignmentResult, Candidate
from toolimit.artifacts import save_json, save_npz
from toolimit.rotations import quaternions_wxyz
from toolimit.scenes.base import pack_scene_params
from toolimit.tools import roll_of

ALIGNMENT_JSON = "alignment.json"
ALIGNED_DEMO_NPZ = "aligned_demo.npz"
#: Every kept candidate's tool poses and parameters, for selection by robot execution (paper).
CANDIDATES_NPZ = "candidates.npz"
#: The search's progress in the output folder while it runs (removed when it ends).
CHECKPOINT_JSON = "alignment_checkpoint.json"


def alignment_finished(folder: str | Path) -> bool:
    """An alignment in ``folder`` finished with candidates (no checkpoint of an interrupted search left)."""
    folder = Path(folder)
    return (folder / CANDIDATES_NPZ).is_file() and not (folder / CHECKPOINT_JSON).is_file()


def continuous_quaternions_wxyz(rotation: np.ndarray) -> np.ndarray:
    """(T, 4) unit quaternions (w, x, y, z) of rotations (T, 3, 3), signs chosen without jumps."""
    quaternions = quaternions_wxyz(rotation)
    for t in range(1, len(quaternions)):
        if np.dot(quaternions[t], quaternions[t - 1]) < 0.0:
            quaternions[t] = -quaternions[t]
    return quaternions


def alignment_record(result: AlignmentResult, demo_path: str, **extra: Any) -> dict[str, Any]:
    """The content of ``alignment.json``: the shared keys, the search's diagnostics, ``extra``."""
    best = result.best
    return {
        "tool": result.tool,
        "world": result.world,
        "demo": demo_path,
        "seed": result.seed,
        "samples_tried": result.samples_tried,
        "samples_rejected": result.samples_rejected,
        "samples_to_first_candidate": result.samples_to_first_candidate,
        "wall_time_s": round(result.wall_time_s, 3),
        "best_index": None if best is None else best.index,
        "candidates": [_candidate_record(c) for c in result.candidates],
        "rejection_reasons": result.rejection_reasons,
        "plane": result.plane,
        "keypoints": result.keypoints.tolist(),
        "min_element_distance_m": result.min_distance,
        "config": result.config.to_dict(),
        **extra,
    }


def _candidate_record(candidate: Candidate) -> dict[str, Any]:
    sample = candidate.sample.to_dict()
    return {
        "reward": candidate.reward,
        "params": sample.pop("params"),
        "sample_index": candidate.index,
        "replay_rewards": candidate.replay_rewards.tolist(),
        "episode_cut": None if candidate.cut is None else candidate.cut.record(),
        **sample,
    }


def aligned_demo_arrays(result: AlignmentResult, candidate: Candidate) -> dict[str, Any]:
    """The arrays of ``aligned_demo.npz`` for ``candidate``: its episode (the cut motion of a timed
    goal, :mod:`toolimit.align.episode_cut`, with the cut's frames; else the whole motion) as the tool
    alone reached it (:meth:`AlignmentResult.episode_poses`): head, handle and roll are those of the
    reached poses, so that the demo and its tool-frame poses describe one motion."""
    aligned = result.aligned_motion(candidate)[0]
    poses = result.episode_poses(candidate)
    length = np.linalg.norm(aligned.handle - aligned.head, axis=-1)  # (T,) m, the demo's tool length
    cut: dict[str, Any] = {}
    if candidate.cut is not None:
        length = candidate.cut.apply(length)
        cut = {
            "first_reward_frame": np.int64(candidate.cut.first_reward_frame),
            "episode_start_frame": np.int64(candidate.cut.start),
        }
    arrays: dict[str, Any] = {
        "head": poses.position,
        "handle": poses.position + length[:, None] * poses.rotation[:, :, 2],
        "fps": np.float64(aligned.fps),
        "tool": np.str_(result.tool),
        "tip_position": poses.position,
        "tip_quaternion_wxyz": continuous_quaternions_wxyz(poses.rotation),
        "roll": roll_of(poses.rotation),
        "scene_world": np.str_(result.world),
        "keypoints": result.keypoints,
        "reward": np.float64(candidate.reward),
    }
    return arrays | cut | pack_scene_params(candidate.sample.params)


def candidates_arrays(result: AlignmentResult) -> dict[str, Any]:
    """The arrays of ``candidates.npz``: every candidate's episode poses (K, T, ...), NaN after its
    own ``episode_frames`` (K,) (the cut episodes of a timed goal differ in length), and parameters
    (K, ...); for a timed goal also ``first_reward_frame`` and ``episode_start_frame`` (K,), frames
    of the aligned motion."""
    motions = [result.episode_poses(candidate) for candidate in result.candidates]
    frames = np.array([len(poses.position) for poses in motions])

    def padded(values: list[np.ndarray]) -> np.ndarray:
        stacked = np.full((len(values), frames.max()) + values[0].shape[1:], np.nan)
        for k, value in enumerate(values):
            stacked[k, : len(value)] = value
        return stacked

    cuts = [candidate.cut for candidate in result.candidates]
    cut_arrays: dict[str, Any] = {}
    if all(cut is not None for cut in cuts):
        cut_arrays = {
            "first_reward_frame": np.array([cut.first_reward_frame for cut in cuts if cut is not None]),
            "episode_start_frame": np.array([cut.start for cut in cuts if cut is not None]),
        }
    arrays: dict[str, Any] = {
        "tip_position": padded([poses.position for poses in motions]),
        "tip_quaternion_wxyz": padded([continuous_quaternions_wxyz(poses.rotation) for poses in motions]),
        "episode_frames": frames,
        "fps": np.float64(result.demo.fps),
        "tool": np.str_(result.tool),
        "scene_world": np.str_(result.world),
        "alignment_reward": np.array([candidate.reward for candidate in result.candidates]),
        "sample_index": np.array([candidate.index for candidate in result.candidates]),
        **cut_arrays,
    }
    names = result.candidates[0].sample.params
    stacked = {
        name: np.stack([np.asarray(c.sample.params[name], dtype=float) for c in result.candidates]) for name in names
    }
    return arrays | pack_scene_params(stacked)


def write_alignment(result: AlignmentResult, out_dir: str | Path, demo_path: str, **extra: Any) -> list[Path]:
    """Write ``alignment.json`` and, when a candidate exists, ``aligned_demo.npz`` and
    ``candidates.npz`` (atomically).

    Without a candidate, a stale ``aligned_demo.npz`` / ``candidates.npz`` from an earlier run is
    removed so that the folder never pairs a record with another run's motion. ``extra`` keys
    (JSON values) are added to the record. Returns the paths written.
    """
    out_dir = Path(out_dir)
    written = []
    best = result.best
    demo_file, candidates_file = out_dir / ALIGNED_DEMO_NPZ, out_dir / CANDIDATES_NPZ
    if best is not None:
        save_npz(demo_file, **aligned_demo_arrays(result, best))
        save_npz(candidates_file, **candidates_arrays(result))
        written += [demo_file, candidates_file]
    else:
        demo_file.unlink(missing_ok=True)
        candidates_file.unlink(missing_ok=True)
    save_json(out_dir / ALIGNMENT_JSON, alignment_record(result, demo_path, **extra))
    written.append(out_dir / ALIGNMENT_JSON)
    return written
