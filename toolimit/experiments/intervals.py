"""95 % bootstrap intervals of the figure over training seeds and evaluation episodes.

Three statistics, each a point estimate with a percentile bootstrap interval, deterministic (a
numpy ``Generator`` seeded with :data:`BOOTSTRAP_SEED` for each call, so that one interval does not
depend on which others were computed):

- :func:`seed_episode_interval`, one cell: the mean over seeds of each seed's mean over its
  episodes, with a two-level (cluster) bootstrap: draw the seeds with replacement, then, for each
  seed drawn, its episodes with replacement. That is what "over seeds and episodes" means: a
  seed's episodes share its policy, so they are not independent draws of the method's outcome and
  resampling them as one pool would take 60 correlated episodes for 60 independent ones. Its
  limits: with S seeds the outer level has only S-multisets to draw from (3 seeds: 10 of them),
  and the bootstrap's variance of a mean of S values is (S-1)/S of the usual estimate, so with 3
  seeds the interval is too narrow and covers less than 95 %: read it as a lower bound on the
  spread, not a guarantee. With one seed it is an interval over episodes alone and says nothing
  of another training run.
- :func:`interquartile_mean`, a method over demonstrations: the 25 % trimmed mean of the runs'
  scores (every seed on every demonstration) with a stratified bootstrap, the runs of each
  demonstration resampled among themselves (Agarwal et al., "Deep reinforcement learning at the
  edge of the statistical precipice", NeurIPS 2021; ``rliable.metrics.aggregate_iqm``).
- :func:`probability_of_improvement`, one method against another: P(X > Y) on a demonstration is
  the share of pairs of runs (one of each) in which X scores more, ties counting half (the
  Mann-Whitney U statistic over the number of pairs), averaged over the demonstrations both were
  measured on; the runs of each method on each demonstration resampled independently (Agarwal et
  al.; ``rliable.metrics.probability_of_improvement`` with its ``StratifiedIndependentBootstrap``).

The last two use :func:`scipy.stats.bootstrap`, which resamples each sample it is given
independently of the others: one sample per demonstration (and per method) is the stratified
bootstrap. ``rliable`` itself is not used: it installs seaborn (so matplotlib), pandas and arch.
A demonstration with a single run is a stratum with nothing to resample: it enters every
resample as it is (scipy needs two values a sample); when no stratum has two runs there is no
interval (``low`` and ``high`` None).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import scipy.stats
from numpy.typing import ArrayLike

#: The bootstrap's interval.
CONFIDENCE = 0.95
#: Bootstrap resamples of each statistic.
RESAMPLES = 10_000
#: Every statistic's own generator's seed.
BOOTSTRAP_SEED = 0


@dataclass(frozen=True)
class Interval:
    """A point estimate and its 95 % interval (``low``, ``high``; None: no interval, one run)."""

    value: float
    low: float | None
    high: float | None

    def record(self) -> dict[str, Any]:
        """JSON-ready form."""
        return asdict(self)


def seed_episode_interval(per_seed: Sequence[ArrayLike], resamples: int = RESAMPLES) -> Interval:
    """The mean over seeds of each seed's mean over its episodes, ``per_seed[s]`` (E_s,), with the
    two-level bootstrap interval over seeds then episodes (module docstring)."""
    samples = [np.asarray(values, dtype=float) for values in per_seed]
    if not samples or any(len(values) == 0 for values in samples):
        raise ValueError("an interval needs at least one seed, each with at least one episode")
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    count = len(samples)
    drawn = rng.integers(count, size=(resamples, count))  # (B, S): which seed fills each place
    # means[s, b, k]: seed s's episodes resampled for place k of resample b (used where drawn == s)
    means = np.stack(
        [values[rng.integers(len(values), size=(resamples, count, len(values)))].mean(axis=2) for values in samples]
    )
    resampled = np.take_along_axis(means, drawn[None], axis=0)[0].mean(axis=1)  # (B,)
    low, high = np.quantile(resampled, [(1 - CONFIDENCE) / 2, (1 + CONFIDENCE) / 2])
    return Interval(float(np.mean([values.mean() for values in samples])), float(low), float(high))


def interquartile_mean(runs: Sequence[ArrayLike]) -> Interval:
    """The interquartile mean of every run's score, ``runs[m]`` (N_m,) the runs on demonstration
    m, with the stratified bootstrap interval (module docstring)."""

    def iqm(*samples: np.ndarray, axis: int = -1) -> np.ndarray:
        return scipy.stats.trim_mean(np.concatenate(samples, axis=-1), 0.25, axis=-1)

    return _stratified(iqm, [np.asarray(r, dtype=float) for r in runs])


def probability_of_improvement(x: Sequence[ArrayLike], y: Sequence[ArrayLike]) -> Interval:
    """P(X > Y) averaged over demonstrations, ``x[m]`` and ``y[m]`` the runs' scores of the two
    methods on demonstration m, with the stratified bootstrap interval (module docstring)."""
    if len(x) != len(y) or not x:
        raise ValueError(f"scores on {len(x)} and {len(y)} demonstrations: both need the same ones, at least one")
    tasks = len(x)

    def improvement(*samples: np.ndarray, axis: int = -1) -> np.ndarray:
        pairs = [
            np.mean(
                (a[..., :, None] > b[..., None, :]) + 0.5 * (a[..., :, None] == b[..., None, :]),
                axis=(-2, -1),
            )
            for a, b in zip(samples[:tasks], samples[tasks:])
        ]
        return np.mean(pairs, axis=0)

    return _stratified(improvement, [np.asarray(s, dtype=float) for s in (*x, *y)])


def _stratified(statistic: Callable[..., np.ndarray], samples: list[np.ndarray]) -> Interval:
    """``statistic(*samples)`` with :func:`scipy.stats.bootstrap`'s percentile interval, each sample
    resampled on its own; samples of one value held as they are (module docstring)."""
    if any(sample.ndim != 1 or len(sample) == 0 for sample in samples):
        raise ValueError("every stratum needs a one-dimensional, non-empty array of scores")
    value = float(statistic(*samples))
    resampled = [k for k, sample in enumerate(samples) if len(sample) > 1]
    if not resampled:
        return Interval(value, None, None)

    def with_fixed(*drawn: np.ndarray, axis: int = -1) -> np.ndarray:
        batch = drawn[0].shape[:-1]
        full = [np.broadcast_to(sample, (*batch, len(sample))) for sample in samples]
        for k, sample in zip(resampled, drawn):
            full[k] = sample
        return statistic(*full)

    result = scipy.stats.bootstrap(
        [samples[k] for k in resampled],
        with_fixed,
        n_resamples=RESAMPLES,
        vectorized=True,
        axis=-1,
        confidence_level=CONFIDENCE,
        method="percentile",
        random_state=np.random.default_rng(BOOTSTRAP_SEED),
    )
    interval = result.confidence_interval
    return Interval(value, float(interval.low), float(interval.high))
