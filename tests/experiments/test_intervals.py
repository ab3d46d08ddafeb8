"""The figure's intervals on data whose answer is known."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.experiments.intervals import interquartile_mean, probability_of_improvement, seed_episode_interval


def test_constant_episodes_give_a_zero_width_interval() -> None:
    interval = seed_episode_interval([np.full(20, 3.0)] * 3)
    assert (interval.value, interval.low, interval.high) == (3.0, 3.0, 3.0)


def test_the_cell_interval_holds_its_mean_and_spans_the_seeds_spread() -> None:
    """Three seeds whose policies differ (every episode of one succeeds, another's none): the
    interval reaches from all-failure to all-success, wider than the same 60 episodes taken as one
    seed would give."""
    seeds = [np.ones(20), np.zeros(20), np.r_[np.ones(10), np.zeros(10)]]
    interval = seed_episode_interval(seeds)
    assert interval.value == pytest.approx(0.5)
    assert interval.low <= interval.value <= interval.high
    assert interval.low == pytest.approx(0.0) and interval.high == pytest.approx(1.0)
    pooled = seed_episode_interval([np.concatenate(seeds)])
    assert pooled.value == pytest.approx(0.5) and pooled.high - pooled.low < 0.3


def test_one_seeds_interval_is_the_episodes_binomial_one() -> None:
    """400 episodes, 200 successes: the 95 % interval's half-width is 1.96 sqrt(p (1 - p) / n) = 0.049."""
    interval = seed_episode_interval([np.r_[np.ones(200), np.zeros(200)]])
    assert (interval.high - interval.low) / 2 == pytest.approx(0.049, abs=0.005)
    assert interval.low < 0.5 < interval.high


def test_intervals_are_deterministic() -> None:
    rng = np.random.default_rng(3)
    seeds = [rng.random(20) for _ in range(3)]
    assert seed_episode_interval(seeds) == seed_episode_interval([s.copy() for s in seeds])
    runs = [rng.random(3) for _ in range(5)]
    assert interquartile_mean(runs) == interquartile_mean([r.copy() for r in runs])


def test_the_interquartile_mean_drops_the_outer_quarters() -> None:
    """Eight runs on four demonstrations: the two lowest and two highest are left out."""
    iqm = interquartile_mean([[0.0, 0.5], [0.5, 0.6], [0.6, 0.7], [0.7, 10.0]])
    assert iqm.value == pytest.approx(np.mean([0.5, 0.6, 0.6, 0.7]))
    assert iqm.low <= iqm.value <= iqm.high


def test_the_stratified_bootstrap_resamples_within_each_demonstration() -> None:
    """Every demonstration's runs agree: resampling within one changes nothing, so the interval has
    no width even though the demonstrations differ (a bootstrap over all runs pooled would have)."""
    iqm = interquartile_mean([[0.2, 0.2, 0.2], [0.5, 0.5, 0.5], [0.6, 0.6, 0.6], [0.9, 0.9, 0.9]])
    assert (iqm.value, iqm.low, iqm.high) == (pytest.approx(0.55), pytest.approx(0.55), pytest.approx(0.55))


def test_one_run_per_demonstration_has_no_interval() -> None:
    iqm = interquartile_mean([[0.2], [0.5], [0.6], [0.9]])
    assert iqm.value == pytest.approx(0.55) and (iqm.low, iqm.high) == (None, None)


def test_probability_of_improvement_is_one_when_one_dominates_and_a_half_when_identical() -> None:
    better, worse = [[0.9, 1.0, 0.95], [1.0, 1.0]], [[0.0, 0.1, 0.2], [0.5, 0.4]]
    dominates = probability_of_improvement(better, worse)
    assert (dominates.value, dominates.low, dominates.high) == (1.0, 1.0, 1.0)
    assert probability_of_improvement(worse, better).value == 0.0
    same = probability_of_improvement(better, better)
    assert same.value == 0.5 and same.low <= 0.5 <= same.high


def test_probability_of_improvement_is_the_mann_whitney_share_averaged_over_demonstrations() -> None:
    """Demonstration 1: x beats y in 2 of 4 pairs and ties 1 (2.5 / 4); demonstration 2: x wins (1)."""
    x, y = [[1.0, 0.5], [1.0]], [[0.5, 0.8], [0.0]]
    assert probability_of_improvement(x, y).value == pytest.approx((2.5 / 4 + 1.0) / 2)


def test_scores_of_different_demonstrations_are_refused() -> None:
    with pytest.raises(ValueError, match="same ones"):
        probability_of_improvement([[1.0]], [[1.0], [0.0]])
    with pytest.raises(ValueError, match="at least one episode"):
        seed_episode_interval([np.ones(3), np.ones(0)])
