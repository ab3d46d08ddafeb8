"""Automatic domain randomisation (ADR) of the goal box position: boundary tests on success.

Under ADR (``adr=True`` of :class:`~toolimit.learn.simulator.TaskSimulator`, ``toolimit learn
--adr``) every reset places each instance's goal box at an (x, y) drawn uniformly inside the
current bounds (:class:`AdrBounds`, world frame, m), and the policy observes it (below). The bounds start at
the aligned position (the task's) and move by boundary tests, run during PPO by
:class:`~toolimit.learn.adr_callback.AdrCallback`:

* every ``every`` updates (:data:`EVERY`), one coordinate and one of its two bounds are picked at
  random (from the seeded generator of :class:`AdrState`, saved in checkpoints so that a resume is
  exact), and one extra batch of episodes runs with that coordinate pinned at that bound (the other
  uniform inside its bounds), the policy sampling its Gaussian as in training; each episode's
  success (the scene's own test, the paper's) joins that bound's buffer, if its box stood at the
  bound (below);
* once a bound's buffer holds :data:`DECISION_EPISODES` episodes (two batches of 16), their success
  rate decides: >= :data:`PUSH_SUCCESS` (0.8) moves the bound out by :data:`DELTA` (0.05 m),
  <= :data:`PULL_SUCCESS` (0.2) moves it in by DELTA (never past the aligned value), in between
  it stays; the buffer is then emptied, so every decision rests on episodes at the current bound;
* the bounds never leave the paper's 100 x 90 cm rectangle around the aligned position (x +-0.5 m,
  y +-0.45 m, :data:`HALF_RANGE`).

This is the rule of OpenAI's ADR (Akkaya et al. 2019, "Solving Rubik's Cube with a Robot Hand",
algorithm 1: a buffer of boundary performances per bound, a decision once it holds m entries,
expand at or above t_H, shrink at or below t_L, the buffer cleared), with the paper's success as
the performance. The authors' code (``docs/original_setup.md#adr``) pushes on a batch's mean return
above 0.5, a tenth of what a spade's success takes, so their bounds grew where the policy failed;
here a bound moves out only where the policy already succeeds at it in 4 episodes of 5, stricter
than a heat-map position's standard (half of its episodes, :mod:`toolimit.learn.heat_map`) because
pushing at 0.5 let the training collapse. With 32 episodes a bound where the policy truly succeeds
90 % of the time is pushed with probability 0.96, at 60 % with 0.01 (binomial). Their reset never
passed the sampled position to the scene, a bug not reproduced here.

Only the coordinates the scene uses are randomised (:attr:`AdrBounds.axes`): x and y in 3D, x alone
in the planar x-z world, whose box ignores y. A position that makes the scene invalid (the box on
the deposit, outside the world) is redrawn (up to :data:`REDRAWS` times, then the aligned position
is used), and a bound is not pushed to a value where no position is valid (:func:`boundary_test`).
An episode whose box fell back to the aligned position was not played at the bound, so its success
says nothing of it: it never joins a buffer. A bound where no box position inside the other bounds
is valid (the near x bound whose whole y range stands on the deposit) is not tested: another bound
is picked from the same generator, and if none is placeable the test is skipped; the learning
record counts both (``repicked``, ``skipped``), so that no buffer fills with successes not earned
at its bound. The default period :data:`EVERY` (8 updates) is the longest that grows the bounds as
fast as testing every 2 updates, measured by ``benchmarks/adr_schedule.py``
(``docs/domain_randomisation.md#domain-randomisation`` gives the figures).

What the policy observes: the box's offset from the aligned position in units of
:data:`BOX_OFFSET_UNIT` (0.1 m; :meth:`AdrBounds.observed`), and, after cloning, the first layer's
weights on those two inputs (policy and value networks) are zeroed
(:func:`toolimit.learn.ppo.blind_to_goal_box`). The clone saw the aligned box only, where the offset
is 0, so it is unchanged there and starts PPO blind to the box elsewhere, instead of with weights
that cloning never constrained; in world metres the box's inputs were too small for Adam's steps to
shape the output soon (``docs/results/adr.md`` has the runs).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from toolimit.errors import InputError
from toolimit.scenes.base import ParameterSpec, Scene

#: The scene parameter ADR moves, per instance: the spades' goal box.
GOAL_BOX = "goal_position"
#: Half sizes (m, world x and y) of the paper's 100 x 90 cm range around the aligned position.
HALF_RANGE = np.array([0.5, 0.45])
#: Step of a bound, m (the authors').
DELTA = 0.05
#: Boundary episodes behind one decision on a bound (OpenAI's buffer length m).
DECISION_EPISODES = 32
#: Success rates at the bound at or above which it is pushed out, at or below which pulled in.
PUSH_SUCCESS = 0.8
PULL_SUCCESS = 0.2
#: Default PPO updates between two boundary tests (module docstring).
EVERY = 8
#: Draws of an instance's box position before falling back to the aligned one.
REDRAWS = 100
#: Seed stream of the ADR generator, apart from the environments' (``[seed, ADR_STREAM]``).
ADR_STREAM = 0xAD2
#: Unit of the observed goal box offset, m: the policy observes (box - aligned) / BOX_OFFSET_UNIT
#: (module docstring, "What the policy observes").
BOX_OFFSET_UNIT = 0.1
#: The rule a checkpoint's ADR state was written under: checkpoints of earlier rules (1: the return
#: rule, whose state had no buffers; 2: buffers took episodes at the aligned box, or the policy
#: observed the box in world metres) are refused rather than resumed under different decisions or
#: observations.
RULE_VERSION = 3


def goal_box_spec(scene: Scene) -> ParameterSpec:
    """The goal box's parameter spec of ``scene``; InputError for a tool without a goal box."""
    for spec in scene.parameters:
        if spec.name == GOAL_BOX and spec.kind == "position":
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

    def observed(self, positions: np.ndarray) -> np.ndarray:
        """(B, 2) what the policy observes of box ``positions`` (B, >= 2) world m: the offset from
        the aligned position in units of :data:`BOX_OFFSET_UNIT` (0 at the aligned box)."""
        return (np.asarray(positions, dtype=float)[:, :2] - self.aligned) / BOX_OFFSET_UNIT

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
        self, rng: np.random.Generator, count: int, valid: Callable[[int, np.ndarray], bool] = lambda *_: True
    ) -> tuple[np.ndarray, np.ndarray]:
        """(count, 2) positions uniform inside the bounds, each redrawn while ``valid(i, position)``
        says no for instance i (at most REDRAWS times, then the aligned position), m, and (count,)
        whether each was placed inside the bounds (False: it fell back to the aligned position).
        Draws the same numbers for an instance whatever ``valid`` says about later ones."""
        positions = np.empty((count, 2))
        placed = np.ones(count, dtype=bool)
        for i in range(count):
            for _ in range(REDRAWS):
                positions[i] = rng.uniform(self.low, self.high)
                if valid(i, positions[i]):
                    break
            else:
                positions[i], placed[i] = self.aligned, False
        return positions, placed

    def placeable(self, rng: np.random.Generator, valid: Callable[[np.ndarray], bool]) -> bool:
        """Whether some draw inside these bounds is valid (REDRAWS tries)."""
        return any(valid(rng.uniform(self.low, self.high)) for _ in range(REDRAWS))

    def record(self) -> dict[str, list[float]]:
        """JSON-ready bounds: ``adr_low``, ``adr_high`` [x, y], world frame, m."""
        return {"adr_low": self.low.tolist(), "adr_high": self.high.tolist()}


def _empty_buffers() -> list[list[list[bool]]]:
    return [[[], []], [[], []]]


@dataclass
class AdrState:
    """What the boundary tests change and a checkpoint keeps: the bounds (shared with the
    environment's simulator), the tests' generator, the update last tested at, each bound's buffer
    of boundary-episode successes (``buffers[axis][side]``, emptied at each decision), the tests
    so far."""

    bounds: AdrBounds
    rng: np.random.Generator
    tested_at: int = 0
    buffers: list[list[list[bool]]] = field(default_factory=_empty_buffers)
    tests: list[dict[str, Any]] = field(default_factory=list)

    def state_dict(self) -> dict[str, Any]:
        """JSON-ready state (for checkpoints)."""
        return {
            "rule_version": RULE_VERSION,
            **self.bounds.record(),
            "rng": self.rng.bit_generator.state,
            "tested_at": self.tested_at,
            "buffers": self.buffers,
            "tests": self.tests,
        }

    def load_state_dict(self, state: dict[str, Any], source: str) -> None:
        """Restore a :meth:`state_dict` read from ``source`` (the bounds object is updated in
        place); InputError naming ``source`` for a state of an earlier rule (:data:`RULE_VERSION`)."""
        if state.get("rule_version") != RULE_VERSION:
            raise InputError(
                f"{source}: this checkpoint was written by an earlier ADR rule and cannot be resumed "
                "under the current one; start a new output folder"
            )
        self.bounds.low[:] = state["adr_low"]
        self.bounds.high[:] = state["adr_high"]
        self.rng.bit_generator.state = state["rng"]
        self.tested_at = int(state["tested_at"])
        self.buffers = [[[bool(s) for s in side] for side in axis] for axis in state["buffers"]]
        self.tests = list(state["tests"])

    def record(self, every: int) -> dict[str, Any]:
        """The learning record's ``adr`` entry: period, rule, aligned position, bounds, range, tests."""
        return {
            "every": every,
            "rule": {
                "decision_episodes": DECISION_EPISODES,
                "push_success": PUSH_SUCCESS,
                "pull_success": PULL_SUCCESS,
                "delta_m": DELTA,
            },
            "aligned": self.bounds.aligned.tolist(),
            **self.bounds.record(),
            "range_m": (self.bounds.high - self.bounds.low).tolist(),
            "repicked": sum(bool(t["refused"]) and t["skipped"] is None for t in self.tests),
            "skipped": sum(t["skipped"] is not None for t in self.tests),
            "unplaced_episodes": sum(t["episodes"] - t["placed"] for t in self.tests),
            "tests": self.tests,
        }


@dataclass(frozen=True)
class BoundaryBatch:
    """The episodes of one boundary test: each one's success (B,), whether each one's box stood
    inside the pinned bounds (B,) (False: no valid position was found, it stood at the aligned one),
    and their mean goal reward at the last step (spade: spheres in the box)."""

    successes: np.ndarray
    placed: np.ndarray
    goal_reward_mean: float


def boundary_test(
    state: AdrState,
    episodes_at: Callable[[AdrBounds], BoundaryBatch],
    placeable: Callable[[AdrBounds], bool] = lambda _: True,
) -> dict[str, Any]:
    """One boundary test (module docstring): pick a coordinate and a side with ``state.rng`` (again,
    among the bounds not yet refused, while ``placeable`` refuses the bounds pinned there; skipped
    if it refuses them all), run ``episodes_at`` the bounds pinned there, add the successes of the
    episodes placed there to that bound's buffer and, once it holds DECISION_EPISODES, decide and
    empty it; a push happens only if ``placeable`` accepts the bounds pinned at the new value.
    Appends and returns the test's record: axis, side, bound (None if skipped), the bounds refused
    before it (``refused``, e.g. "x low"), why it was skipped (``skipped``, None if run), the
    episodes run, those placed at the bound and their successes, the batch's goal reward, the
    decision and the buffer's success rate behind it, the bound after."""
    bounds = state.bounds
    axis = int(state.rng.choice(bounds.axes))
    side = int(state.rng.integers(2))
    refused: list[tuple[int, int]] = []
    while not placeable(bounds.pinned(axis, side)):
        refused.append((axis, side))
        remaining = [(a, s) for a in bounds.axes for s in (0, 1) if (a, s) not in refused]
        if not remaining:
            record = _test_record(refused, None, None, None, "no bound has a valid box position")
            state.tests.append(record)
            return record
        axis, side = remaining[int(state.rng.integers(len(remaining)))]
    before = bounds.bound(axis, side)
    batch = episodes_at(bounds.pinned(axis, side))
    placed = np.asarray(batch.placed, dtype=bool)
    successes = np.asarray(batch.successes, dtype=bool)[placed]
    buffer = state.buffers[axis][side]
    buffer.extend(bool(s) for s in successes)
    after, decision, rate = before, None, None
    if len(buffer) >= DECISION_EPISODES:
        rate = float(np.mean(buffer))
        decision = "hold"
        if rate >= PUSH_SUCCESS:
            pushed = bounds.moved(axis, side, outwards=True)
            if pushed != before and placeable(bounds.pinned(axis, side, pushed)):
                after, decision = pushed, "push"
        elif rate <= PULL_SUCCESS:
            after = bounds.moved(axis, side, outwards=False)
            decision = "pull" if after != before else "hold"
        buffer.clear()
    (bounds.low, bounds.high)[side][axis] = after
    record = _test_record(refused, axis, side, before, None) | {
        "episodes": len(placed),
        "placed": int(np.sum(placed)),
        "successes": int(np.sum(successes)),
        "goal_reward_mean": float(batch.goal_reward_mean),
        "decision": decision,
        "success_rate": rate,
        "after": after,
    }
    state.tests.append(record)
    return record


def _name(axis: int, side: int) -> str:
    return f"{'xy'[axis]} {('low', 'high')[side]}"


def _test_record(
    refused: list[tuple[int, int]], axis: int | None, side: int | None, bound: float | None, skipped: str | None
) -> dict[str, Any]:
    """A test's record as a skipped test leaves it (no episodes, no decision); a run test overrides
    the episodes' entries."""
    return {
        "axis": None if axis is None else "xy"[axis],
        "side": None if side is None else ("low", "high")[side],
        "bound": bound,
        "refused": [_name(a, s) for a, s in refused],
        "skipped": skipped,
        "episodes": 0,
        "placed": 0,
        "successes": 0,
        "goal_reward_mean": None,
        "decision": None,
        "success_rate": None,
        "after": bound,
    }
