"""Synthetic Panda joint trajectories for the export tests."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from toolimit.artifacts import save_npz

PANDA_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
#: a comfortable configuration, well inside every Panda joint range (rad)
PANDA_MIDDLE = np.array([0.0, -0.3, 0.0, -1.8, 0.0, 1.6, 0.8])


def bump(amplitude: float, omega: float, times: np.ndarray) -> np.ndarray:
    """amplitude (1 - cos(omega t))^2 / 4: rises from rest (zero velocity and acceleration) to
    ``amplitude`` at half a period and back to rest at a full period (rad, t in s, omega rad/s)."""
    return amplitude * (1.0 - np.cos(omega * times)) ** 2 / 4.0


@pytest.fixture
def write_trajectory(tmp_path: Path) -> Callable[..., Path]:
    """Write DIR/trajectory.npz for q (T+1, 7) sampled every dt; returns DIR."""

    def write(q: np.ndarray, dt: float, name: str = "trajopt") -> Path:
        directory = tmp_path / name
        save_npz(directory / "trajectory.npz", q=q, v=np.diff(q, axis=0) / dt, base=np.array([0.2, -0.1, 1.5]),
                 joint_names=np.array(PANDA_JOINTS), dt=dt)
        return directory

    return write


def slow_smooth(dt: float = 1.0 / 24.0, duration: float = 4.0) -> np.ndarray:
    """(T+1, 7) a gentle motion of every joint around PANDA_MIDDLE, one full period (rest to rest)."""
    times = np.arange(round(duration / dt) + 1) * dt
    omega = 2.0 * np.pi / duration
    return PANDA_MIDDLE + np.outer(bump(1.0, omega, times), [0.4, 0.3, -0.3, 0.4, 0.5, -0.4, 0.6])
