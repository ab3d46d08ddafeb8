"""Same seed, same sand: whether the particle kernels were just compiled or loaded from numba's cache."""

from __future__ import annotations

import os
import subprocess
import sys

_REPLAY = """
import numpy as np
from toolimit.scenes import replay
from toolimit.scenes.registry import make_scene
from toolimit.scenes.spatial.scoop import scripted_scoop

scene = make_scene("spade", "3d")
params = {"sand_position": np.array([0.5, 0.0, 0.0]), "sand_yaw": 0.0, "goal_position": np.array([0.0, 0.8, 0.0])}
rewards = replay(scene, params, np.random.default_rng(0), scripted_scoop(params), batch_size=4)
print(rewards.tolist(), scene.sphere_positions.tobytes().hex())
"""


def test_compiled_and_cached_kernels_give_the_same_sand(tmp_path):
    """One process compiles the kernels into an empty cache, the next loads them: the same scripted
    scoop must leave every sphere at the same place (bit for bit: one machine, one build)."""
    env = os.environ | {"NUMBA_CACHE_DIR": str(tmp_path / "numba_cache")}
    runs = [
        subprocess.run([sys.executable, "-c", _REPLAY], env=env, capture_output=True, text=True, check=True).stdout
        for _ in range(2)
    ]
    assert any((tmp_path / "numba_cache").rglob("*.nbi")), "the first run wrote no cache"
    assert runs[0] == runs[1]
