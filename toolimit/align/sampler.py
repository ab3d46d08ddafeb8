"""Drawing one alignment sample and applying it to a demonstration.

A sample is the paper's random guess of everything a video does not show: the trajectory scale,
a vertical offset, the tool roll (constant between consecutive keypoints) and the scene
parameters, whose element positions come from a Gaussian mixture around the keypoint positions of
the transformed head path. Frames: world, metres, z up, ground at z = 0; angles in radians.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial.distance import pdist

from toolimit.align.config import IN_PLANE_ROLLS, AlignmentConfig
from toolimit.demos.tool_demo import ToolDemo
from toolimit.scenes.base import ParameterSpec
from toolimit.tools import ToolPose, tool_poses


def minimum_element_distance(points: np.ndarray) -> float:
    """d_th = 0.1 (d_max - d_min), metres, over all pairs of the trajectory points (T, 3)."""
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3 or points.shape[0] < 2:
        raise ValueError(f"points: expected shape (T, 3) with T >= 2, got {points.shape}")
    distances = pdist(points)
    return 0.1 * float(distances.max() - distances.min())


def sample_element_positions(
    keypoints: np.ndarray,
    n_elements: int,
    covariance: np.ndarray,
    min_distance: float,
    rng: np.random.Generator,
    weights: np.ndarray | None = None,
    on_ground: np.ndarray | None = None,
    max_attempts: int = 100,
) -> np.ndarray | None:
    """(n_elements, 3) element positions x_j ~ sum_i w_i N(k_i, Sigma), metres, world frame.

    Args:
        keypoints: (K, 3) mixture means k_i (keypoint positions of the head path).
        n_elements: number of positions to draw.
        covariance: (3, 3) Sigma of every mixture component, m^2.
        min_distance: every pair of drawn positions must be at least this far apart, metres.
        rng: the only source of randomness.
        weights: (K,) mixture weights (normalised here); None for uniform.
        on_ground: (n_elements,) bool, True for elements standing on the ground (z := 0);
            None: none are.
        max_attempts: whole sets drawn before giving up.

    Returns:
        The positions, or None if no set met ``min_distance`` within ``max_attempts`` draws (the
        search counts it as a rejected sample).
    """
    keypoints = np.asarray(keypoints, dtype=float)
    if keypoints.ndim != 2 or keypoints.shape[1] != 3 or keypoints.shape[0] == 0:
        raise ValueError(f"keypoints: expected shape (K, 3) with K >= 1, got {keypoints.shape}")
    covariance = np.asarray(covariance, dtype=float)
    if covariance.shape != (3, 3):
        raise ValueError(f"covariance: expected shape (3, 3), got {covariance.shape}")
    n_keypoints = keypoints.shape[0]
    if weights is None:
        weights = np.full(n_keypoints, 1.0 / n_keypoints)
    else:
        weights = np.asarray(weights, dtype=float)
        if weights.shape != (n_keypoints,) or np.any(weights < 0) or weights.sum() <= 0:
            raise ValueError(f"weights: expected {n_keypoints} non-negative values, got {weights}")
        weights = weights / weights.sum()
    ground = np.zeros(n_elements, bool) if on_ground is None else np.asarray(on_ground, bool)
    if ground.shape != (n_elements,):
        raise ValueError(f"on_ground: expected shape ({n_elements},), got {ground.shape}")
    for _ in range(max_attempts):
        components = rng.choice(n_keypoints, size=n_elements, p=weights)
        positions = rng.multivariate_normal(np.zeros(3), covariance, size=n_elements, method="eigh")
        positions = positions + keypoints[components]
        positions[ground, 2] = 0.0
        if n_elements < 2 or pdist(positions).min() >= min_distance:
            return positions
    return None


@dataclass(frozen=True)
class AlignmentSample:
    """One random alignment of a demonstration with a scene.

    Attributes:
        scale: trajectory scale (the motion shrinks about the ground point under the head path's
            centroid; the tool keeps its length).
        z_offset: vertical shift of the scaled trajectory, metres.
        rolls: (K - 1,) tool roll about its axis, radians, one per segment between consecutive
            keypoints (frame k_i starts segment i; the last frame belongs to the last segment).
        params: scene parameters: position parameters (3,) world points, uniform ones floats.
    """

    scale: float
    z_offset: float
    rolls: np.ndarray
    params: dict[str, np.ndarray | float]

    def to_dict(self) -> dict[str, object]:
        """Plain JSON-ready values."""
        return {
            "scale": float(self.scale),
            "z_offset": float(self.z_offset),
            "rolls": [float(r) for r in self.rolls],
            "params": params_to_json(self.params),
        }


def params_to_json(params: Mapping[str, np.ndarray | float]) -> dict[str, object]:
    """Scene parameters as JSON values (lists for positions, floats for scalars)."""
    return {name: np.asarray(value, dtype=float).tolist() for name, value in params.items()}


def scale_centre(demo: ToolDemo) -> np.ndarray:
    """(3,) the point the trajectory scale shrinks about: the ground under the head path's centroid.

    Scaling about a ground point keeps the ground where it is (a scoop at ground level stays at
    ground level), as the original code did by scaling about the demonstrator's feet.
    """
    centre = demo.head.mean(axis=0)
    centre[2] = 0.0
    return centre


def transformed_demo(demo: ToolDemo, scale: float, z_offset: float) -> ToolDemo:
    """The demo scaled about :func:`scale_centre` then lifted by ``z_offset`` metres."""
    return demo.scaled(scale, about=scale_centre(demo)).translated(np.array([0.0, 0.0, z_offset]))


def roll_per_frame(n_frames: int, keypoints: np.ndarray, rolls: np.ndarray) -> np.ndarray:
    """(T,) roll of each frame, radians: ``rolls[i]`` from keypoint i up to keypoint i + 1."""
    keypoints = np.asarray(keypoints, dtype=int)
    rolls = np.asarray(rolls, dtype=float)
    if rolls.shape != (len(keypoints) - 1,):
        raise ValueError(f"rolls: expected one per keypoint segment ({len(keypoints) - 1}), got {rolls.shape}")
    segment = np.searchsorted(keypoints, np.arange(n_frames), side="right") - 1
    return rolls[np.clip(segment, 0, len(rolls) - 1)]


def draw_alignment_sample(
    demo: ToolDemo,
    keypoints: np.ndarray,
    parameters: Sequence[ParameterSpec],
    config: AlignmentConfig,
    covariance: np.ndarray,
    min_distance: float,
    rng: np.random.Generator,
    plane: str | None = None,
) -> AlignmentSample | None:
    """Draw scale, z offset, rolls and scene parameters; None if the elements cannot be placed.

    ``keypoints`` are frame indices of ``demo`` (at least two: first and last frame);
    ``min_distance`` is d_th in metres; ``covariance`` is the (3, 3) mixture Sigma, m^2; ``plane``
    is the planar world's plane (None in 3D): in a plane of ``IN_PLANE_ROLLS`` the whole motion takes
    the in-plane roll nearest to the first drawn roll, since a blade cannot turn over between
    keypoints without leaving the plane (the generator is used exactly as in 3D).
    """
    scale = float(rng.choice(np.asarray(config.scales, dtype=float)))
    z_offset = float(rng.normal(0.0, config.z_offset_std))
    rolls = rng.uniform(-np.pi, np.pi, size=len(keypoints) - 1)
    if plane in IN_PLANE_ROLLS:  # one face for the whole motion: turning over would leave the plane
        facing_zero, facing_pi = IN_PLANE_ROLLS[plane]
        rolls = np.full_like(rolls, facing_zero if abs(rolls[0]) < np.pi / 2 else facing_pi)
    params: dict[str, np.ndarray | float] = {}
    for spec in parameters:
        if spec.kind == "uniform":
            params[spec.name] = float(rng.uniform(spec.low, spec.high))
    positions = [spec for spec in parameters if spec.kind == "position"]
    if positions:
        head = transformed_demo(demo, scale, z_offset).head
        placed = sample_element_positions(
            head[keypoints],
            len(positions),
            covariance,
            min_distance,
            rng,
            on_ground=np.array([spec.on_ground for spec in positions]),
            max_attempts=config.max_attempts,
        )
        if placed is None:
            return None
        params.update({spec.name: position for spec, position in zip(positions, placed)})
    ordered = {spec.name: params[spec.name] for spec in parameters}
    return AlignmentSample(scale=scale, z_offset=z_offset, rolls=rolls, params=ordered)


def apply_alignment_sample(
    demo: ToolDemo, keypoints: np.ndarray, sample: AlignmentSample
) -> tuple[ToolDemo, np.ndarray, ToolPose]:
    """The aligned demo, its per-frame roll (T,) in radians and its tool poses (T, ...) in the world.

    The tool poses follow the tool-frame convention of :mod:`toolimit.tools` (origin at the head,
    z towards the handle end, roll about z).
    """
    aligned = transformed_demo(demo, sample.scale, sample.z_offset)
    roll = roll_per_frame(demo.n_frames, keypoints, sample.rolls)
    return aligned, roll, tool_poses(aligned.head, aligned.handle, roll)
