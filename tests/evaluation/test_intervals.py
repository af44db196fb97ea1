"""Confidence intervals for claims: hand-computed t-intervals, paired differences, margins."""

import math

import numpy as np
import pytest

from fusetrack.evaluation import (
    interval_values,
    mean_interval,
    median_interval,
    median_shown_positive,
    paired_interval,
    paired_median_interval,
    shown_positive,
    within_margin,
)


def test_mean_interval_by_hand():
    # values 1, 2, 3: mean 2, sd 1, SE 1/sqrt(3); t_{0.975, 2} = 4.302653
    mean, half = mean_interval([1.0, 2.0, 3.0, float("nan")])
    assert mean == 2.0
    assert half == pytest.approx(4.302653 / math.sqrt(3), rel=1e-6)


def test_too_few_values_show_nothing():
    assert mean_interval([1.5]) == (1.5, math.inf)
    mean, half = mean_interval([])
    assert math.isnan(mean) and half == math.inf
    assert not shown_positive((1.5, math.inf)) and not within_margin((1.5, math.inf), 1.5, 9.0)


def test_paired_interval_removes_the_common_part():
    rng = np.random.default_rng(0)
    common = rng.normal(0.0, 10.0, 50)  # run-to-run spread far above the effect
    a, b = common + 0.3 + rng.normal(0, 0.05, 50), common
    assert shown_positive(paired_interval(a, b))  # paired: the 0.3 gap is clear
    assert not shown_positive(mean_interval(a - b.mean()))  # unpaired-like: lost in the spread
    assert not shown_positive(paired_interval(b, a))


def test_within_margin_needs_the_whole_interval_inside():
    assert within_margin((1.0, 0.15), 1.1, 0.3)
    assert not within_margin((1.0, 0.25), 1.1, 0.3)
    assert not within_margin((float("nan"), 0.0), 1.0, 1.0)
    assert interval_values((1.23456, math.inf)) == [1.235, math.inf]


def test_median_interval_by_order_statistics():
    # n = 15: P(Bin(15, 1/2) <= 3) = 0.0176 <= 0.025 < P(<= 4) = 0.0592, so [x_(4), x_(12)]
    med, lo, hi = median_interval(np.arange(1.0, 16.0))
    assert (med, lo, hi) == (8.0, 4.0, 12.0)
    # n = 6: P(<= 0) = 1/64 <= 0.025: [min, max]; n = 5: 1/32 > 0.025: nothing is shown
    assert median_interval([3.0, 1.0, 2.0, 6.0, 5.0, 4.0]) == (3.5, 1.0, 6.0)
    assert median_interval([1.0, 2.0, 3.0, 4.0, 5.0])[1:] == (-math.inf, math.inf)


def test_paired_median_ignores_one_diverged_run():
    a = np.full(12, 1.0)
    b = np.full(12, 0.8)
    b[0] = 50.0  # one run of b diverged: the mean says b is worse, the typical run says better
    assert not shown_positive(paired_interval(b, a))
    assert median_shown_positive(paired_median_interval(a, b))
    assert not median_shown_positive(paired_median_interval(b, a))
