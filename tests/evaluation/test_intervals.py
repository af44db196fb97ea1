"""Confidence intervals for claims: hand-computed t-intervals, paired differences, margins."""

import math

import numpy as np
import pytest

from fusetrack.evaluation import (
    interval_values,
    mean_interval,
    paired_interval,
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
