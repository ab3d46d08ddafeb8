"""Automatic domain randomisation (ADR) of the goal box position: the authors' boundary test.

Under ADR (``adr=True`` of :class:`~toolimit.learn.simulator.TaskSimulator`, ``toolimit learn
--adr``) every reset places each instance's goal box at an (x, y) drawn uniformly inside the
current bounds (:class:`AdrBounds`, world frame, m), and the policy observes it. The bounds start at
the aligned position (the task's) and move by the rule of the authors' code
(``docs/original_setup.md#adr``), run during PPO by
:class:`~toolimit.learn.adr_callback.AdrCallback`:

* every ``every`` updates, one coordinate and one of its two bounds are picked at random (from the
  seeded generator of :class:`AdrState`, saved in checkpoints so that a resume is exact), and one
  extra batch of episodes runs with that coordinate pinned at that bound (the other uniform inside
  its bounds), the policy sampling its Gaussian as in training;
* mean return > :data:`PUSH_THRESHOLD` (0.5): the bound moves out by :data:`DELTA` (0.05 m);
  mean return < :data:`PULL_THRESHOLD` (0): it moves in by DELTA, never past the aligned value.
  Returns are per-step averages of the goal reward, as the authors' (reward / H per step), so 0.5
  is half a sphere in the box per step on average;
* the bounds never leave the paper's 100 x 90 cm rectangle around the aligned position (x +-0.5 m,
  y +-0.45 m, :data:`HALF_RANGE`); the authors' code had +-0.5 m on both and never passed the
  sampled position to the scene, a bug not reproduced here.

Only the coordinates the scene uses are randomised (:attr:`AdrBounds.axes`): x and y in 3D, x alone
in the planar x-z world, whose box ignores y. A position that makes the scene invalid (the box on
the deposit, outside the world) is redrawn (up to :data:`REDRAWS` times, then the aligned position
is used), and a bound is not pushed to a value where no position is valid (:func:`boundary_test`).
The default period :data:`EVERY` is 2 updates, not the authors' 100 iterations: they ran 10,000
iterations (100 tests); our runs make 50-300 updates, and the full rectangle needs at least 38
successful pushes in 3D (10 + 10 + 9 + 9), 20 in the plane. One test batch (B episodes) every two
updates (2 x 2B episodes with the authors' preset) adds a quarter to the simulation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from toolimit.errors import InputError
from toolimit.scenes.base import ParameterSpec, Scene

#: The scene parameter ADR moves: the spades' goal box (a ``per_instance`` position).
GOAL_BOX = "goal_position"
#: Half sizes (m, world x and y) of the paper's 100 x 90 cm range around the aligned position.
HALF_RANGE = np.array([0.5, 0.45])
#: Step of a bound (m) and the mean returns above which it is pushed out, below which pulled in.
DELTA = 0.05
PUSH_THRESHOLD = 0.5
PULL_THRESHOLD = 0.0
#: Default PPO updates between two boundary tests (module docstring).
EVERY = 2
#: Draws of an instance's box position before falling back to the aligned one.
REDRAWS = 100
#: Seed stream of the ADR generator, apart from the environments' (``[seed, ADR_STREAM]``).
ADR_STREAM = 0xAD2


def goal_box_spec(scene: Scene) -> ParameterSpec:
    """The goal box's parameter spec of ``scene``; InputError for a tool without a goal box."""
    for spec in scene.parameters:
        if spec.name == GOAL_BOX and spec.per_instance:
            return spec
    raise InputError(f"--adr randomises the goal box position, and the {scene.tool} scene has none (only the spades)")


@dataclass
class AdrBounds:
    """The current range of the goal box position: [low, high] per coordinate (x, y), world frame, m.

    Attributes:
        aligned: (2,) the task's box position, where the bounds start.
        axes: the coordinates randomised (0 = x, 1 = y); the others stay at the aligned value.
        low, high: (2,) the current bounds, low <= aligned <= high.
    """

    aligned: np.ndarray
    axes: tuple[int, ...]
    low: np.ndarray = field(default_factory=lambda: np.zeros(2))
    high: np.ndarray = field(default_factory=lambda: np.zeros(2))

    @classmethod
    def at(cls, aligned: np.ndarray, axes: tuple[int, ...]) -> AdrBounds:
        """Bounds collapsed on ``aligned`` (2,) (the start of ADR), randomising ``axes`` (of 0, 1)."""
        aligned = np.asarray(aligned, dtype=float)[:2].copy()
        return cls(aligned, tuple(a for a in axes if a in (0, 1)), aligned.copy(), aligned.copy())

    @property
    def limits(self) -> np.ndarray:
        """(2, 2) rows low, high: the paper's rectangle around the aligned position, m."""
        return np.stack([self.aligned - HALF_RANGE, self.aligned + HALF_RANGE])

    def bound(self, axis: int, side: int) -> float:
        """The low (side 0) or high (side 1) bound of coordinate ``axis``, m."""
        return float((self.low, self.high)[side][axis])

    def pinned(self, axis: int, side: int, value: float | None = None) -> AdrBounds:
        """A copy with coordinate ``axis`` fixed at its ``side`` bound (or at ``value``)."""
        at = self.bound(axis, side) if value is None else value
        low, high = self.low.copy(), self.high.copy()
        low[axis] = high[axis] = at
        return AdrBounds(self.aligned, self.axes, low, high)

    def moved(self, axis: int, side: int, outwards: bool) -> float:
        """The ``side`` bound of ``axis`` after one DELTA step out (``outwards``) or in, m: within
        the rectangle, never past the aligned value."""
        sign = (-1.0, 1.0)[side] * (1.0 if outwards else -1.0)
        value = self.bound(axis, side) + sign * DELTA
        inner, outer = sorted((float(self.aligned[axis]), float(self.limits[side, axis])))
        return float(np.clip(value, inner, outer))

    def draw(
        self, rng: np.random.Generator, count: int, valid: Callable[[np.ndarray], bool] = lambda _: True
    ) -> np.ndarray:
        """(count, 2) positions uniform inside the bounds, each redrawn while ``valid`` says no (at
        most REDRAWS times, then the aligned position), m. Draws the same numbers whatever ``valid``
        says about other instances."""
        positions = np.empty((count, 2))
        for i in range(count):
            for _ in range(REDRAWS):
                positions[i] = rng.uniform(self.low, self.high)
                if valid(positions[i]):
                    break
            else:
                positions[i] = self.aligned
        return positions

    def placeable(self, rng: np.random.Generator, valid: Callable[[np.ndarray], bool]) -> bool:
        """Whether some draw inside these bounds is valid (REDRAWS tries)."""
        return any(valid(rng.uniform(self.low, self.high)) for _ in range(REDRAWS))

    def record(self) -> dict[str, list[float]]:
        """JSON-ready bounds: ``adr_low``, ``adr_high`` [x, y], world frame, m."""
        return {"adr_low": self.low.tolist(), "adr_high": self.high.tolist()}


@dataclass
class AdrState:
    """What the boundary tests change and a checkpoint keeps: the bounds (shared with the
    environment's simulator), the tests' generator, the update last tested at, the tests so far."""

    bounds: AdrBounds
    rng: np.random.Generator
    tested_at: int = 0
    tests: list[dict[str, Any]] = field(default_factory=list)

    def state_dict(self) -> dict[str, Any]:
        """JSON-ready state (for checkpoints)."""
        return {
            **self.bounds.record(),
            "rng": self.rng.bit_generator.state,
            "tested_at": self.tested_at,
            "tests": self.tests,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore a :meth:`state_dict` (the bounds object is updated in place)."""
        self.bounds.low[:] = state["adr_low"]
        self.bounds.high[:] = state["adr_high"]
        self.rng.bit_generator.state = state["rng"]
        self.tested_at = int(state["tested_at"])
        self.tests = list(state["tests"])

    def record(self, every: int) -> dict[str, Any]:
        """The learning record's ``adr`` entry: period, aligned position, bounds, range, tests."""
        return {
            "every": every,
            "aligned": self.bounds.aligned.tolist(),
            **self.bounds.record(),
            "range_m": (self.bounds.high - self.bounds.low).tolist(),
            "tests": self.tests,
        }


def boundary_test(
    state: AdrState,
    mean_return: Callable[[AdrBounds], float],
    placeable: Callable[[AdrBounds], bool] = lambda _: True,
) -> dict[str, Any]:
    """One boundary test (module docstring): pick a coordinate and a side with ``state.rng``, get
    ``mean_return`` of a batch with the bounds pinned there, and move that bound; a push happens
    only if ``placeable`` accepts the bounds pinned at the new value. Appends and returns the test's
    record (axis, side, bound, return, the bound after)."""
    bounds = state.bounds
    axis = int(state.rng.choice(bounds.axes))
    side = int(state.rng.integers(2))
    before = bounds.bound(axis, side)
    value = mean_return(bounds.pinned(axis, side))
    after = before
    if value > PUSH_THRESHOLD:
        pushed = bounds.moved(axis, side, outwards=True)
        after = pushed if placeable(bounds.pinned(axis, side, pushed)) else before
    elif value < PULL_THRESHOLD:
        after = bounds.moved(axis, side, outwards=False)
    (bounds.low, bounds.high)[side][axis] = after
    record = {"axis": "xy"[axis], "side": ("low", "high")[side], "bound": before, "return_mean": value, "after": after}
    state.tests.append(record)
    return record
