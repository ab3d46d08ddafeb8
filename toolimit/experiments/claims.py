"""The paper's claims, read off a reproduction's intervals.

Each claim is read per tool, world and robot (a *group*) from the summaries of
:mod:`toolimit.experiments.summary`:

* **succeeds**: the final policy's mean success is at least 0.8 on at least 80 % of the group's
  demonstrations (4 of 5, 5 of 6), as the paper's figure shows its method succeeding;
* **open-loop**: the same of the final policy's exported trajectory replayed open-loop, the
  paper's real-robot experiment (its 100 % on the Panda's spade);
* **within limits**: no control step of any final policy past the robot's velocity or
  acceleration limits ("the resulting policies respect the joint velocity limits");
* **beats sparse PPO**: the probability that the final policy beats PPO on the sparse reward on a
  demonstration (Agarwal et al.'s P(X > Y)) is above 0.5;
* **dense PPO in some cases**: PPO on the dense reward also succeeds (0.8) on at least one
  demonstration ("comparable in some cases");
* **LfD comparable**: the final policy at least draws with LfD from a kinesthetic demonstration,
  P(final > LfD) of 0.5 or more.

A claim counts the items that meet its test three ways: on their whole interval (firmly), on their
point estimate (the mean), and anywhere within their interval (possibly). It **holds** when enough
items meet it firmly; it **holds on the means** when enough do on the means but some of their
intervals reach past the test; it **could hold** when too few do on the means but enough could
within their intervals; else it **does not hold**. Without an interval (one run) an item's three
readings are its value's. An interval from few seeds is too narrow
(:mod:`~toolimit.experiments.intervals`), so "holds" on three seeds is itself a reading with that
limit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from toolimit.experiments.intervals import Interval
from toolimit.experiments.summary import METHOD, CellSummary, MethodSummary

#: The success rate at which a cell succeeds (the rate the results pages call success).
SUCCESS = 0.8
#: The share of a group's demonstrations that must succeed: the paper's scythe, 4 of 5.
DEMONSTRATIONS_SHARE = 0.8
#: The probability of improvement of a draw: above it the final policy beats a baseline.
DRAW = 0.5
#: The baselines of the paper's second and third claims (``toolimit.experiments.cells.METHODS``).
SPARSE_PPO, DENSE_PPO, LFD = "sparse_ppo", "dense_ppo", "lfd"

READINGS = ("holds", "holds on the means", "could hold", "does not hold")


@dataclass(frozen=True)
class ClaimReading:
    """One claim on one group.

    Attributes:
        claim: its name (module docstring).
        tool, world, robot: the group.
        test: what an item must meet, in words.
        items: the items counted (demonstrations, or the one comparison).
        required: how many must meet it.
        firmly, on_the_means, possibly: how many meet it on their whole interval, on their point
            estimate, anywhere within their interval.
        reading: one of :data:`READINGS`.
        failing: the items whose point estimate does not meet it.
    """

    claim: str
    tool: str
    world: str
    robot: str
    test: str
    items: list[str]
    required: int
    firmly: int
    on_the_means: int
    possibly: int
    reading: str
    failing: list[str]

    def record(self) -> dict[str, Any]:
        """JSON-ready form (the ``claims`` entries of ``results.json``)."""
        return asdict(self)


def read_claims(summaries: Sequence[CellSummary], aggregates: Sequence[MethodSummary]) -> list[ClaimReading]:
    """Every claim on every group that has what it needs, groups in the order first met."""
    finals = [s for s in summaries if s.method == METHOD]
    groups = list(dict.fromkeys((s.tool, s.world, s.robot) for s in finals))
    readings = []
    for group in groups:
        cells = [s for s in finals if (s.tool, s.world, s.robot) == group]
        at_least = f">= {SUCCESS:g}"
        success = [(s.demo, s.success) for s in cells]
        readings.append(_count("succeeds", group, f"final success {at_least}", success, _above))
        exported = [(s.demo, s.exported_success) for s in cells if s.exported_success is not None]
        if exported:
            readings.append(_count("open-loop", group, f"exported success, open-loop, {at_least}", exported, _above))
        limited = [(s.demo, s.steps_past_limits) for s in cells if s.steps_past_limits is not None]
        if limited:
            readings.append(_count("within limits", group, "no step past the limits", limited, _none, len(limited)))
        improvement = {
            a.method: (a.improvement, len(a.improvement_demos))
            for a in aggregates
            if (a.tool, a.world, a.robot) == group and a.improvement is not None
        }
        if SPARSE_PPO in improvement:
            readings.append(_improves("beats sparse PPO", group, SPARSE_PPO, *improvement[SPARSE_PPO], at_least=False))
        dense = [(s.demo, s.success) for s in summaries if (s.tool, s.world, s.robot, s.method) == (*group, DENSE_PPO)]
        if dense:
            readings.append(_count("dense PPO in some cases", group, f"dense PPO success {at_least}", dense, _above, 1))
        if LFD in improvement:
            readings.append(_improves("LfD comparable", group, LFD, *improvement[LFD], at_least=True))
    return readings


def _above(value: float) -> bool:
    return value >= SUCCESS


def _none(value: float) -> bool:
    return value <= 0.0


def _count(
    claim: str,
    group: tuple[str, str, str],
    test: str,
    items: Sequence[tuple[str, Interval]],
    meets: Callable[[float], bool],
    required: int | None = None,
) -> ClaimReading:
    """A claim that ``required`` of the group's demonstrations (None: :data:`DEMONSTRATIONS_SHARE`
    of them), ``items`` (demonstration, its interval), meet ``meets``; ``meets`` is monotone, so an
    interval meets it firmly when both its ends do and possibly when either does."""
    ends = [_ends(interval) for _, interval in items]
    return _reading(
        claim,
        group,
        test,
        [demo for demo, _ in items],
        math.ceil(DEMONSTRATIONS_SHARE * len(items) - 1e-9) if required is None else required,
        firmly=sum(meets(low) and meets(high) for low, _, high in ends),
        on_the_means=sum(meets(value) for _, value, _ in ends),
        possibly=sum(meets(low) or meets(high) for low, _, high in ends),
        failing=[demo for (demo, _), (_, value, _) in zip(items, ends) if not meets(value)],
    )


def _improves(
    claim: str, group: tuple[str, str, str], baseline: str, improvement: Interval, demos: int, at_least: bool
) -> ClaimReading:
    """P(final > ``baseline``) on ``demos`` common demonstrations, ``improvement``, above
    :data:`DRAW` (``at_least``: or at it, a draw): one item."""
    low, value, high = _ends(improvement)
    meets = (lambda p: p >= DRAW) if at_least else (lambda p: p > DRAW)
    item = f"P(final > {baseline}) on {demos}"
    return _reading(
        claim,
        group,
        f"P(final > {baseline}) {'>=' if at_least else '>'} {DRAW:g}",
        [item],
        1,
        firmly=int(meets(low)),
        on_the_means=int(meets(value)),
        possibly=int(meets(high)),
        failing=[] if meets(value) else [item],
    )


def _ends(interval: Interval) -> tuple[float, float, float]:
    """(low, value, high); the value three times with no interval."""
    if interval.low is None or interval.high is None:
        return interval.value, interval.value, interval.value
    return interval.low, interval.value, interval.high


def _reading(
    claim: str,
    group: tuple[str, str, str],
    test: str,
    items: list[str],
    required: int,
    firmly: int,
    on_the_means: int,
    possibly: int,
    failing: list[str],
) -> ClaimReading:
    if firmly >= required:
        reading = READINGS[0]
    elif on_the_means >= required:
        reading = READINGS[1]
    elif possibly >= required:
        reading = READINGS[2]
    else:
        reading = READINGS[3]
    return ClaimReading(claim, *group, test, items, required, firmly, on_the_means, possibly, reading, failing)


def claims_table(readings: Sequence[ClaimReading]) -> str:
    """One row per claim and group: the counts of items meeting its test on their whole interval,
    on their mean and within their interval, against how many it needs, and the reading."""
    lines = [
        "| claim | tool | world | robot | test | firmly / on the means / possibly, of | needs | reading | not on the means |",
        "| --- | --- | --- | --- | --- | ---: | ---: | --- | --- |",
    ]
    for r in readings:
        counts = f"{r.firmly} / {r.on_the_means} / {r.possibly}, of {len(r.items)}"
        failing = ", ".join(r.failing) or "-"
        row = (r.claim, r.tool, r.world, r.robot, r.test, counts, str(r.required), f"**{r.reading}**", failing)
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"
