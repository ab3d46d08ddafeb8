"""The tracking cost: targets, residuals and their Jacobians (vs finite differences)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from toolimit.trajopt import PoseTargets, TrackingProblem, TrackingWeights
from toolimit.trajopt.targets import from_original_spade_tip, load_pose_targets

from trajopt_helpers import reachable_path, targets_of


def test_quaternions_match_pinocchio():
    rng = np.random.default_rng(0)
    quaternions = rng.normal(size=(5, 4)) * 3.0  # not normalised: normalised by the loader
    targets = PoseTargets.from_quaternions(rng.normal(size=(5, 3)), quaternions, 24)
    unit = quaternions / np.linalg.norm(quaternions, axis=1, keepdims=True)
    for quaternion, rotation in zip(unit, targets.rotations):
        w, x, y, z = quaternion
        np.testing.assert_allclose(rotation, pin.Quaternion(w, x, y, z).toRotationMatrix(), atol=1e-12)


@pytest.mark.parametrize(
    ("positions", "quaternions", "fps", "message"),
    [
        (np.zeros((3, 2)), np.tile([1.0, 0, 0, 0], (3, 1)), 24, r"\(T, 3\)"),
        (np.zeros((3, 3)), np.tile([1.0, 0, 0, 0], (2, 1)), 24, "2 rows"),
        (np.zeros((3, 3)), np.zeros((3, 4)), 24, "zero or non-finite"),
        (np.zeros((3, 3)), np.tile([1.0, 0, 0, 0], (3, 1)), 0, "fps"),
        (np.full((3, 3), np.nan), np.tile([1.0, 0, 0, 0], (3, 1)), 24, "non-finite"),
    ],
)
def test_bad_targets_are_rejected(positions, quaternions, fps, message):
    with pytest.raises(ValueError, match=message):
        PoseTargets.from_quaternions(positions, quaternions, fps)


def test_load_pose_targets_names_the_file_and_key(tmp_path):
    path = tmp_path / "poses.npz"
    np.savez(path, tip_position=np.zeros((4, 3)), fps=24)
    with pytest.raises(ValueError, match=r"poses.npz: missing keys \['tip_quaternion_wxyz'\]"):
        load_pose_targets(path)
    with pytest.raises(FileNotFoundError, match="nothing.npz"):
        load_pose_targets(tmp_path / "nothing.npz")


def test_original_spade_tip_frame_points_z_at_the_handle(video_demos_dir):
    original = load_pose_targets(video_demos_dir / "spade_video1_aligned.npz")
    converted = from_original_spade_tip(original)
    handle = original.positions - original.rotations @ np.array([0.0, -0.161, 0.369])  # the data README's rule
    axis = (handle - original.positions) / np.linalg.norm(handle - original.positions, axis=1, keepdims=True)
    np.testing.assert_allclose(converted.rotations[:, :, 2], axis, atol=1e-12)
    np.testing.assert_allclose(converted.positions, original.positions)
    np.testing.assert_allclose(np.linalg.det(converted.rotations), 1.0)


def test_original_spade_face_points_up_while_carrying(video_demos_dir):
    """The converted x (the blade's carrying face) points up through the recorded scoop and carry
    (frames 20 to 80 of the clean example recording), as a face holding sand must."""
    converted = from_original_spade_tip(load_pose_targets(video_demos_dir / "spade_example_aligned.npz"))
    assert np.all(converted.rotations[20:81, 2, 0] > 0.85)


def test_residual_jacobian_matches_finite_differences(panda):
    path = reachable_path(panda, 6)
    base = np.array([0.1, -0.2, 0.3])
    targets = targets_of(panda, path[::-1], base)  # a different path, so residuals are not zero
    problem = TrackingProblem(panda, targets, 1 / 24, q_start=path[0], weights=TrackingWeights(1.0, 0.5, 0.01))
    lin = problem.linearise(base, path)
    np.testing.assert_allclose(lin.residuals, problem.pose_residuals(base, path), atol=1e-12)
    assert np.abs(lin.residuals).max() > 1e-2
    eps = 1e-6
    for t in (0, 3, 5):
        numeric = np.zeros((6, 3 + panda.n_joints))
        for i in range(3 + panda.n_joints):
            b, q = base.copy(), path.copy()
            if i < 3:
                b[i] += eps
            else:
                q[t + 1, i - 3] += eps
            numeric[:, i] = (problem.pose_residuals(b, q)[t] - lin.residuals[t]) / eps
        np.testing.assert_allclose(lin.jacobians[t], numeric, atol=2e-5)


def test_cost_is_the_benchmark_objective(panda):
    path = reachable_path(panda, 5)
    base = np.array([0.0, 0.1, -0.2])
    targets = targets_of(panda, path, base + [0.05, 0.0, 0.0])
    benchmark = TrackingWeights(position=1.0, rotation=0.5, velocity=0.01)  # PROBLEM.md's weights
    problem = TrackingProblem(panda, targets, 0.05, q_start=path[0], weights=benchmark)
    terms = problem.cost_terms(base, path)
    pose = 0.0
    for t in range(5):
        placement = panda.tool_placement_world(path[t + 1], base)
        error = pin.log6(pin.SE3(targets.rotations[t], targets.positions[t]).actInv(placement)).vector
        pose += 0.5 * np.sum((np.array([1, 1, 1, 0.5, 0.5, 0.5]) * error) ** 2)
    assert terms["pose"] == pytest.approx(pose, rel=1e-12)
    assert terms["velocity"] == pytest.approx(0.5 * 0.01 * np.sum((np.diff(path, axis=0) / 0.05) ** 2), rel=1e-12)
    assert terms["total"] == pytest.approx(terms["pose"] + terms["velocity"])
