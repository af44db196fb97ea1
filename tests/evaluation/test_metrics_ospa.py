"""OSPA (Schuhmacher, Vo & Vo 2008) on hand cases."""

import numpy as np
import pytest

from fusetrack.core import ConfigError, ShapeError
from fusetrack.evaluation import ospa, ospa_components, ospa_over_time

X = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])


def test_identical_sets_are_zero():
    assert ospa(X, X, c=5.0, p=2) == 0.0
    assert ospa(X[::-1], X, c=5.0) == 0.0  # order does not matter


@pytest.mark.parametrize("p", [1.0, 2.0, 3.0])
def test_one_missing_target(p):
    c, n = 4.0, 3
    expected = (c**p / n) ** (1 / p)
    assert ospa(X[:2], X, c=c, p=p) == pytest.approx(expected)
    assert ospa(X, X[:2], c=c, p=p) == pytest.approx(expected)  # symmetric


def test_known_assignment():
    # estimates near the truths but listed in another order; offsets 1, 2, 0
    Y = np.array([[0.0, 12.0], [1.0, 0.0], [10.0, 0.0]])
    # best assignment: (0,0)->(1,0): 1, (10,0)->(10,0): 0, (0,10)->(0,12): 2
    assert ospa(Y, X, c=10.0, p=1) == pytest.approx(3 / 3)
    assert ospa(Y, X, c=10.0, p=2) == pytest.approx(np.sqrt(5 / 3))
    # cut-off: an error of 2 counts as c = 1.5
    assert ospa(Y, X, c=1.5, p=1) == pytest.approx((1 + 0 + 1.5) / 3)


def test_empty_sets_and_components():
    empty = np.zeros((0, 2))
    assert ospa(empty, empty, c=3.0) == 0.0
    assert ospa(empty, X, c=3.0, p=2) == 3.0
    assert ospa([], X, c=3.0) == 3.0
    loc, card = ospa_components(X[:2] + np.array([0.5, 0.0]), X, c=4.0, p=2)
    assert loc == pytest.approx(np.sqrt(0.5 / 3))
    assert card == pytest.approx(np.sqrt(16 / 3))
    assert ospa(X[:2] + np.array([0.5, 0.0]), X, c=4.0, p=2) == pytest.approx(np.hypot(loc, card))


def test_nan_rows_dropped_and_over_time():
    est = np.vstack([X[:2], [np.nan, np.nan]])
    assert ospa(est, X, c=4.0) == pytest.approx(4.0 / 3)
    d = ospa_over_time([X, X[:2], []], [X, X, X], c=4.0)
    np.testing.assert_allclose(d, [0.0, 4.0 / 3, 4.0])


def test_bad_arguments():
    with pytest.raises(ConfigError, match="c="):
        ospa(X, X, c=0.0)
    with pytest.raises(ConfigError, match="p="):
        ospa(X, X, c=1.0, p=0.5)
    with pytest.raises(ShapeError):
        ospa(np.zeros((2, 3)), X, c=1.0)
    with pytest.raises(ShapeError):
        ospa_over_time([X], [X, X], c=1.0)
