"""Batched conversions between rotation matrices, quaternions and rotation vectors, compiled.

The learning environment turns the B tool rotations into quaternions at every step, and the 3D
scenes interpolate the tool's rotation along every control step (logarithm, then exponential at
each sub-step). scipy's ``Rotation`` takes about 120 and 150 microseconds for these with B = 16,
mostly in per-call checks; these numba loops take about 6 and 14 (``benchmarks/rotation_conversions.py``).

They evaluate scipy's formulas (``scipy.spatial.transform``, 1.17) operation for operation:
Shepperd's method for matrix -> quaternion, the rotation vector of the canonical quaternion
(w >= 0) through atan2 with a Taylor series below 1e-3 rad, and its inverse with the series of
sin(a/2)/a. On this machine they return scipy's results to the last bit (``tests/test_rotations.py``
checks them to 1e-15 against scipy). Unlike scipy they do not project a non-orthogonal matrix onto
the rotations: inputs must be rotation matrices (orthonormal up to rounding, determinant +1), as the
forward kinematics and the interpolation give. Quaternions are (x, y, z, w) unless a name says
``wxyz``. Compiled on first use and cached on disk, like :mod:`toolimit.scenes.spatial.particle_kernels`.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

_jit = nb.njit(cache=True, nogil=True, fastmath=False, error_model="numpy")

#: Below this angle (rad) the rotation vector conversions use their Taylor series (scipy's threshold).
SMALL_ANGLE = 1e-3


@_jit
def _quaternions_xyzw(matrices):  # type: ignore[no-untyped-def]
    """(n, 4) unit quaternions (x, y, z, w) of rotation matrices (n, 3, 3): Shepperd's method."""
    n = matrices.shape[0]
    out = np.empty((n, 4))
    for b in range(n):
        m = matrices[b]
        trace = m[0, 0] + m[1, 1] + m[2, 2]
        choice = 0  # the largest of m00, m11, m22, trace (the first one on ties)
        largest = m[0, 0]
        for c in range(1, 3):
            if m[c, c] > largest:
                choice, largest = c, m[c, c]
        if trace > largest:
            choice = 3
        q = out[b]
        if choice == 3:
            q[0] = m[2, 1] - m[1, 2]
            q[1] = m[0, 2] - m[2, 0]
            q[2] = m[1, 0] - m[0, 1]
            q[3] = 1 + trace
        else:
            i = choice
            j = (i + 1) % 3
            k = (j + 1) % 3
            q[i] = 1 - trace + 2 * m[i, i]
            q[j] = m[j, i] + m[i, j]
            q[k] = m[k, i] + m[i, k]
            q[3] = m[k, j] - m[j, k]
        norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
        for c in range(4):
            q[c] = q[c] / norm
    return out


@_jit
def _rotation_vectors(matrices):  # type: ignore[no-untyped-def]
    """(n, 3) rotation vectors (axis times angle in [0, pi], rad) of rotation matrices (n, 3, 3)."""
    quaternions = _quaternions_xyzw(matrices)
    out = np.empty((matrices.shape[0], 3))
    for b in range(matrices.shape[0]):
        x, y, z, w = quaternions[b, 0], quaternions[b, 1], quaternions[b, 2], quaternions[b, 3]
        # the canonical one of q and -q: w > 0, or the first non-zero of x, y, z positive
        if w < 0 or (w == 0 and (x < 0 or (x == 0 and (y < 0 or (y == 0 and z < 0))))):
            x, y, z, w = -x, -y, -z, -w
        angle = 2 * math.atan2(math.sqrt(x * x + y * y + z * z), w)
        angle2 = angle * angle
        small = angle <= SMALL_ANGLE
        scale = 2 + angle2 / 12 + 7 * angle2 * angle2 / 2880 if small else angle / math.sin(angle / 2.0)
        out[b, 0], out[b, 1], out[b, 2] = scale * x, scale * y, scale * z
    return out


@_jit
def _rotation_matrices(vectors):  # type: ignore[no-untyped-def]
    """(n, 3, 3) rotation matrices of rotation vectors (n, 3), rad."""
    out = np.empty((vectors.shape[0], 3, 3))
    for b in range(vectors.shape[0]):
        vx, vy, vz = vectors[b, 0], vectors[b, 1], vectors[b, 2]
        angle = math.sqrt(vx * vx + vy * vy + vz * vz)
        angle2 = angle * angle
        small = angle <= SMALL_ANGLE
        scale = 0.5 - angle2 / 48 + angle2 * angle2 / 3840 if small else math.sin(angle / 2) / angle
        x, y, z, w = vx * scale, vy * scale, vz * scale, math.cos(angle / 2)
        x2, y2, z2, w2 = x * x, y * y, z * z, w * w
        xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
        m = out[b]
        m[0, 0], m[0, 1], m[0, 2] = x2 - y2 - z2 + w2, 2 * (xy - zw), 2 * (xz + yw)
        m[1, 0], m[1, 1], m[1, 2] = 2 * (xy + zw), -x2 + y2 - z2 + w2, 2 * (yz - xw)
        m[2, 0], m[2, 1], m[2, 2] = 2 * (xz - yw), 2 * (yz + xw), -x2 - y2 + z2 + w2
    return out


def _stacked(array: np.ndarray, tail: tuple[int, ...], name: str) -> np.ndarray:
    """``array`` as a C-contiguous float64 (n, *tail) stack (a single item gets n = 1)."""
    array = np.asarray(array, dtype=float)
    if array.shape[-len(tail) :] != tail:
        raise ValueError(f"{name}: expected shape (..., {', '.join(map(str, tail))}), got {array.shape}")
    return np.ascontiguousarray(array.reshape((-1, *tail)))


def quaternions_wxyz(rotations: np.ndarray) -> np.ndarray:
    """(..., 4) unit quaternions (w, x, y, z) of rotation matrices (..., 3, 3); the sign is Shepperd's
    (as scipy's ``Rotation.from_matrix(R).as_quat(scalar_first=True)``)."""
    matrices = _stacked(rotations, (3, 3), "rotations")
    xyzw = _quaternions_xyzw(matrices)
    return xyzw[:, [3, 0, 1, 2]].reshape((*np.shape(rotations)[:-2], 4))


def rotation_vectors(rotations: np.ndarray) -> np.ndarray:
    """(..., 3) rotation vectors (rad; angle in [0, pi]) of rotation matrices (..., 3, 3): the logarithm."""
    return _rotation_vectors(_stacked(rotations, (3, 3), "rotations")).reshape(np.shape(rotations)[:-1])


def rotation_matrices(vectors: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices of rotation vectors (..., 3), rad: the exponential."""
    return _rotation_matrices(_stacked(vectors, (3,), "vectors")).reshape((*np.shape(vectors), 3))
