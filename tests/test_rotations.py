"""The compiled rotation conversions: scipy's results, the conventions, the shapes."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from toolimit.rotations import SMALL_ANGLE, quaternions_wxyz, rotation_matrices, rotation_vectors


def _rotations() -> np.ndarray:
    """(N, 3, 3): random rotations, small ones on both sides of the series threshold, some near pi,
    products of rotations (rounding as in forward kinematics) and the identity."""
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(600, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.concatenate([np.logspace(-9, -2, 200), np.pi - np.logspace(-10, -1, 200), rng.uniform(0, np.pi, 200)])
    assert np.any(angles < SMALL_ANGLE) and np.any((angles > SMALL_ANGLE) & (angles < 1e-2))
    random = Rotation.random(200, random_state=1).as_matrix()
    products = np.swapaxes(random, 1, 2) @ random[::-1]
    return np.concatenate([Rotation.from_rotvec(axes * angles[:, None]).as_matrix(), random, products, np.eye(3)[None]])


def test_the_conversions_give_scipys_results():
    rotations = _rotations()
    np.testing.assert_allclose(
        quaternions_wxyz(rotations), Rotation.from_matrix(rotations).as_quat(scalar_first=True), rtol=0, atol=1e-15
    )
    vectors = rotation_vectors(rotations)
    np.testing.assert_allclose(vectors, Rotation.from_matrix(rotations).as_rotvec(), rtol=0, atol=1e-14)
    scaled = vectors * np.random.default_rng(1).uniform(0, 1, (len(vectors), 1))
    np.testing.assert_allclose(rotation_matrices(scaled), Rotation.from_rotvec(scaled).as_matrix(), rtol=0, atol=1e-15)


def test_the_exponential_inverts_the_logarithm():
    rotations = _rotations()
    np.testing.assert_allclose(rotation_matrices(rotation_vectors(rotations)), rotations, rtol=0, atol=1e-12)
    assert np.all(np.linalg.norm(rotation_vectors(rotations), axis=-1) <= np.pi + 1e-12)


def test_a_turn_about_z_has_the_expected_quaternion_and_vector():
    angle = 0.7
    rotation = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(quaternions_wxyz(rotation), [np.cos(angle / 2), 0.0, 0.0, np.sin(angle / 2)], atol=1e-15)
    np.testing.assert_allclose(rotation_vectors(rotation), [0.0, 0.0, angle], atol=1e-15)


def test_leading_axes_are_kept():
    rotations = Rotation.random(12, random_state=2).as_matrix().reshape(3, 4, 3, 3)
    assert quaternions_wxyz(rotations).shape == (3, 4, 4)
    assert rotation_vectors(rotations).shape == (3, 4, 3)
    assert rotation_matrices(rotation_vectors(rotations)).shape == (3, 4, 3, 3)
    assert quaternions_wxyz(np.eye(3)).shape == (4,)
    np.testing.assert_allclose(quaternions_wxyz(rotations)[2, 1], quaternions_wxyz(rotations[2, 1]))


@pytest.mark.parametrize("call", [quaternions_wxyz, rotation_vectors])
def test_a_matrix_of_the_wrong_shape_is_refused(call):
    with pytest.raises(ValueError, match=r"rotations: expected shape \(\.\.\., 3, 3\), got \(4, 3, 2\)"):
        call(np.zeros((4, 3, 2)))


def test_a_vector_of_the_wrong_shape_is_refused():
    with pytest.raises(ValueError, match=r"vectors: expected shape \(\.\.\., 3\), got \(4, 2\)"):
        rotation_matrices(np.zeros((4, 2)))
