"""Synthetic, exactly reachable tracking problems for the trajopt tests: targets made by forward kinematics."""

from __future__ import annotations

import numpy as np

from toolimit.trajopt import PoseTargets

FPS = 24.0


def reachable_path(robot, steps: int, amplitude: float = 0.25, speed: float = 0.5) -> np.ndarray:
    """(steps+1, N) smooth joint path from q_neutral, within position and velocity limits
    (|v| <= speed * vlim), joints swinging by up to ``amplitude`` rad."""
    times = np.arange(steps + 1) / FPS
    phases = np.linspace(0.0, 1.0, robot.n_joints)
    frequency = speed * robot.velocity_limit.min() / amplitude
    swing = np.sin(frequency * times[:, None] + 3 * phases) - np.sin(3 * phases)
    path = robot.q_neutral + amplitude * swing
    margin = 1e-3
    path = np.clip(path, robot.lower + margin, robot.upper - margin)
    assert np.all(np.abs(np.diff(path, axis=0)) * FPS <= robot.velocity_limit)
    return path


def targets_of(robot, path: np.ndarray, base: np.ndarray) -> PoseTargets:
    positions, rotations = robot.tool_poses(path[1:], base)
    return PoseTargets(positions, rotations, FPS)
