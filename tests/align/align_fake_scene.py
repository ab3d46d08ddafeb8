"""A tiny deterministic scene for the alignment tests (no physics, microseconds per step).

One ground "target" element and a uniform "radius": an instance earns reward 1 when the tool head
passes within ``radius`` (times a per-instance factor in [0.8, 1.2] drawn at reset) of the target. Samples
whose target has x below ``reject_below_x`` are invalid, to exercise rejection counting.
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.base import InvalidSceneParameters, ParameterSpec
from toolimit.tools import ToolPose


class FakeTargetScene:
    tool = "spade"
    world = "planar"
    control_dt = 1.0 / 24.0

    def __init__(self, reject_below_x: float = -np.inf, radius_high: float = 0.1) -> None:
        self.reject_below_x = reject_below_x
        self.parameters = (
            ParameterSpec("target", "position", (-5.0, -5.0, 0.0), (5.0, 5.0, 0.0), on_ground=True),
            ParameterSpec("radius", "uniform", 0.0, radius_high, unit="m"),
        )
        self.batch_size = 0
        self.steps = 0

    def invalid_reason(self, params) -> str | None:
        if float(params["target"][0]) < self.reject_below_x:
            return f"target: x {float(params['target'][0]):.3f} below {self.reject_below_x}"
        return None

    def reset(self, params, rng: np.random.Generator, batch_size: int = 1) -> None:
        reason = self.invalid_reason(params)
        if reason:
            raise InvalidSceneParameters(reason)
        self.target = np.asarray(params["target"], dtype=float)
        self.radius = float(params["radius"]) * rng.uniform(0.8, 1.2, size=batch_size)
        self.batch_size = batch_size
        self.hit = np.zeros(batch_size, bool)
        self.steps = 0
        self.last_head = None

    def step(self, tool_pose: ToolPose) -> None:
        head = np.broadcast_to(tool_pose.position, (self.batch_size, 3))
        self.hit |= np.linalg.norm(head - self.target, axis=1) < self.radius
        self.steps += 1
        self.last_head = head[0].copy()

    def goal_reward(self) -> np.ndarray:
        return self.hit.astype(float)

    def dense_reward(self) -> np.ndarray:
        return self.goal_reward()

    def is_success(self) -> np.ndarray:
        return self.hit.copy()

    def footprints(self, params) -> np.ndarray:
        target = np.asarray(params["target"], dtype=float)
        return np.array([[target[0], target[1], 0.05, 0.05, 0.0]])

    def snapshot(self) -> dict[str, np.ndarray]:
        return {"target": self.target.copy(), "radius": np.array(self.radius[0])}


def make_demo(n_frames: int = 60, fps: float = 24.0):
    """A scoop-like head motion in the x-z plane: down to the ground, along, up; tool 0.4 m."""
    from toolimit.demos import ToolDemo

    t = np.linspace(0.0, 1.0, n_frames)
    head = np.stack([0.6 * t, np.zeros_like(t), 0.05 + 0.3 * (2 * t - 1) ** 2], axis=1)
    tilt = 0.6 * np.sin(np.pi * t)
    axis = np.stack([-np.sin(tilt), np.zeros_like(t), np.cos(tilt)], axis=1)
    return ToolDemo(head, head + 0.4 * axis, fps, "spade", source="test scoop")


class UnreachableTargetScene(FakeTargetScene):
    """A target no tool reaches (radius ~ 0): every sample earns zero reward."""

    def __init__(self) -> None:
        super().__init__(radius_high=1e-9)


class CrashingScene(FakeTargetScene):
    """Raises after ``resets`` resets, like a search killed half-way."""

    def __init__(self, resets: int) -> None:
        super().__init__()
        self.resets_left = resets

    def reset(self, params, rng: np.random.Generator, batch_size: int = 1) -> None:
        if self.resets_left == 0:
            raise RuntimeError("simulated crash")
        self.resets_left -= 1
        super().reset(params, rng, batch_size)
