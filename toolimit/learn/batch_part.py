"""A part of a batch of instances, and the random draws that make it the same part of the same batch.

A batch of B instances may be simulated in pieces (:mod:`toolimit.learn.split_simulator`: one piece
per process). Each piece draws its reset randomness for the whole batch, from a copy of the batch's
generator, and keeps its own instances' share: so instance i starts from the same numbers whatever
the pieces, and the generator ends in the same state in every piece.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, cast

import numpy as np


@dataclass(frozen=True)
class BatchPart:
    """Instances ``start`` .. ``stop`` - 1 of a batch of ``total``."""

    start: int
    stop: int
    total: int

    def __post_init__(self) -> None:
        if not 0 <= self.start < self.stop <= self.total:
            raise ValueError(f"need 0 <= start < stop <= total, got {self.start}, {self.stop}, {self.total}")

    @staticmethod
    def whole(total: int) -> BatchPart:
        return BatchPart(0, total, total)

    @staticmethod
    def split(total: int, pieces: int) -> list[BatchPart]:
        """``pieces`` consecutive parts of sizes differing by at most one (the larger first)."""
        bounds = np.cumsum([0] + [len(piece) for piece in np.array_split(np.arange(total), pieces)])
        return [BatchPart(int(a), int(b), total) for a, b in zip(bounds[:-1], bounds[1:])]

    @property
    def size(self) -> int:
        return self.stop - self.start

    @property
    def is_whole(self) -> bool:
        return self.size == self.total

    def of(self, batch: np.ndarray) -> np.ndarray:
        """This part's rows of an array over the whole batch (first axis B)."""
        return batch[self.start : self.stop]

    def generator(self, rng: np.random.Generator) -> np.random.Generator:
        """``rng`` itself for the whole batch; else a stand-in whose per-instance draws (first axis
        of ``size`` the part's size) are drawn for the whole batch and cut to the part
        (:class:`PartDraws`). A scene's reset takes it in place of the generator."""
        return rng if self.is_whole else cast(np.random.Generator, PartDraws(rng, self))


class PartDraws:
    """The per-instance draws of a scene's reset (``uniform``, ``normal``) for a :class:`BatchPart`.

    Only draws whose first axis is the instances can be cut; any other draw raises ValueError (a
    scene drawing instance by instance, as the planar ones do, cannot be split)."""

    def __init__(self, rng: np.random.Generator, part: BatchPart):
        self.rng, self.part = rng, part

    def uniform(self, low: Any = 0.0, high: Any = 1.0, size: Any = None) -> np.ndarray:
        return self._draw(self.rng.uniform, low, high, size)

    def normal(self, loc: Any = 0.0, scale: Any = 1.0, size: Any = None) -> np.ndarray:
        return self._draw(self.rng.normal, loc, scale, size)

    def _draw(self, method: Callable[..., np.ndarray], a: Any, b: Any, size: Any) -> np.ndarray:
        shape = tuple(np.atleast_1d(size)) if size is not None else ()
        if not shape or shape[0] != self.part.size:
            raise ValueError(
                f"a draw of size {size!r} is not one per instance of a part of {self.part.size}: "
                "this scene cannot be split over processes (use one)"
            )
        return self.part.of(method(a, b, size=(self.part.total, *shape[1:])))
