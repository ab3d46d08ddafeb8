"""Speed of the compiled rotation conversions (``toolimit.rotations``) against scipy's ``Rotation``.

Run: ``python benchmarks/rotation_conversions.py [--repeats 5]``. Times, in the same run, the two
conversions the 3D learning environment makes at every control step with B = 16 instances:

* the tool's quaternions: ``quaternions_wxyz(R)`` against
  ``Rotation.from_matrix(R).as_quat(scalar_first=True)``, R (16, 3, 3);
* the tool's motion along the step (``scenes.spatial.tool_motion.interpolate_poses``, 10 sub-steps):
  the logarithm of 16 relative rotations, then the exponential at 11 fractions of it, against
  ``Rotation.from_matrix(...).as_rotvec()`` and ``Rotation.from_rotvec(...).as_matrix()``.

Prints microseconds per call (the minimum over ``--repeats`` runs of 2,000 calls each, CPU time),
the ratio scipy / toolimit, and whether the results are equal to the last bit on this machine (they
are meant to be: the same formulas in the same order). The first call compiles the kernels if numba's
cache is cold; a warm-up call keeps that out of the figures.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
from scipy.spatial.transform import Rotation

from toolimit.rotations import quaternions_wxyz, rotation_matrices, rotation_vectors

BATCH = 16
FRACTIONS = np.linspace(0.0, 1.0, 11)


def _microseconds(call: Callable[[], np.ndarray], repeats: int, calls: int = 2000) -> float:
    """Minimum over ``repeats`` of the CPU time of one call, microseconds."""
    call()
    best = np.inf
    for _ in range(repeats):
        start = time.process_time()
        for _ in range(calls):
            call()
        best = min(best, (time.process_time() - start) / calls)
    return best * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per figure; the minimum is kept")
    args = parser.parse_args()
    start, end = Rotation.random(2 * BATCH, random_state=0).as_matrix().reshape(2, BATCH, 3, 3)
    relative = np.swapaxes(start, -1, -2) @ end

    def scipy_quaternions() -> np.ndarray:
        return Rotation.from_matrix(start).as_quat(scalar_first=True)

    def scipy_interpolation() -> np.ndarray:
        vectors = Rotation.from_matrix(relative).as_rotvec()
        steps = (FRACTIONS[:, None, None] * vectors[None]).reshape(-1, 3)
        return Rotation.from_rotvec(steps).as_matrix().reshape(len(FRACTIONS), BATCH, 3, 3)

    def toolimit_quaternions() -> np.ndarray:
        return quaternions_wxyz(start)

    def toolimit_interpolation() -> np.ndarray:
        return rotation_matrices(FRACTIONS[:, None, None] * rotation_vectors(relative)[None])

    for name, reference, ours in (
        (f"quaternions of {BATCH} rotations", scipy_quaternions, toolimit_quaternions),
        (f"log of {BATCH} rotations + exp at {len(FRACTIONS)} fractions", scipy_interpolation, toolimit_interpolation),
    ):
        scipy_us, toolimit_us = _microseconds(reference, args.repeats), _microseconds(ours, args.repeats)
        equal = np.array_equal(reference(), ours())
        print(
            f"{name}: scipy {scipy_us:.1f} us, toolimit {toolimit_us:.1f} us, ratio {scipy_us / toolimit_us:.1f}; "
            f"equal to the last bit: {equal}"
        )


if __name__ == "__main__":
    main()
