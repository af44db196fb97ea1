"""Cell arcs and arc-mean likelihoods (Kushwaha 2010, Eqs. 32, 34, 35) on hand-computed cases."""

import numpy as np
import pytest

from fusetrack.core.errors import ShapeError
from fusetrack.sensors.detection_function import (
    AngularSampling,
    arc_mean_matrix,
    cell_arcs,
    interpolate,
    mixture_arc_mean,
    normalize_likelihood,
)


def test_cell_arc_hand_computed():
    # Sensor at the origin, cell centred at (2, 0) with half-size 0.5: vertices at (1.5, ±0.5) and
    # (2.5, ±0.5); the widest bearings are ±atan(0.5 / 1.5).
    lo, hi, inside = cell_arcs((0.0, 0.0), 0.0, [[2.0, 0.0]], 0.5)
    assert lo[0] == pytest.approx(-np.arctan(0.5 / 1.5))
    assert hi[0] == pytest.approx(np.arctan(0.5 / 1.5))
    assert not inside[0]
    # The heading rotates the arc: a sensor facing +y sees the same cell at -90°.
    lo, hi, _ = cell_arcs((0.0, 0.0), np.pi / 2, [[2.0, 0.0]], 0.5)
    assert 0.5 * (lo[0] + hi[0]) == pytest.approx(-np.pi / 2)


def test_cell_arc_across_the_wrap_and_inside():
    # A cell straight behind the sensor (bearing ±π) must give a narrow arc, not a 2π one.
    lo, hi, inside = cell_arcs((0.0, 0.0), 0.0, [[-3.0, 0.0], [0.1, -0.1]], 0.5)
    assert hi[0] - lo[0] == pytest.approx(2 * np.arctan(0.5 / 2.5))
    assert inside[1] and hi[1] - lo[1] == pytest.approx(2 * np.pi)


def test_arc_width_shrinks_as_one_over_range():
    r = np.array([5.0, 10.0, 20.0])
    lo, hi, _ = cell_arcs((0.0, 0.0), 0.0, np.column_stack([r, np.zeros(3)]), 0.25)
    width = hi - lo
    # exact: the near corners at (r - h, ±h) bound the arc
    assert np.allclose(width, 2 * np.arctan(0.25 / (r - 0.25)))
    assert width[1] / width[2] == pytest.approx(2.0, rel=0.03)  # ≈ 1/r


def test_interpolation_is_piecewise_linear_and_periodic():
    s = AngularSampling.beams(36)
    v = np.arange(36.0)
    # halfway between beam 0 (0°) and beam 1 (10°): Eq. 34 with w = 1/2
    assert interpolate(s, v, np.deg2rad(5.0)) == pytest.approx(0.5)
    # between 350° (value 35) and 360° = 0° (value 0)
    assert interpolate(s, v, np.deg2rad(355.0)) == pytest.approx(17.5)
    assert interpolate(s, v, np.deg2rad(-5.0)) == pytest.approx(17.5)


@pytest.mark.parametrize("periodic", [True, False])
def test_arc_mean_matrix_equals_numerical_mean(periodic):
    rng = np.random.default_rng(0)
    s = AngularSampling.beams(36) if periodic else AngularSampling.camera_bins(np.deg2rad(60), 160)
    v = rng.random(s.size)
    if periodic:
        lo = np.array([-0.2, 3.0, 6.1, 1.0])
        hi = lo + np.array([0.4, 0.5, 0.3, 2 * np.pi])
    else:
        lo = np.array([-0.4, -0.1, 0.2, -0.6])
        hi = lo + np.array([0.05, 0.2, 0.1, 0.3])  # the last one runs past the edge
    w = arc_mean_matrix(s, lo, hi)
    for a, b, row in zip(lo, hi, w):
        theta = np.linspace(a, b, 200001)
        assert row @ v == pytest.approx(np.mean(interpolate(s, v, theta)), rel=1e-4)
    assert np.allclose(w.sum(axis=1), 1.0)  # the mean of a constant is the constant


def test_arc_mean_of_hand_computed_cell():
    # λ = 1 on beam 0 only (a tent of half-width 10° around 0°); the arc [-5°, 5°] has mean 0.75.
    s = AngularSampling.beams(36)
    v = np.zeros(36)
    v[0] = 1.0
    w = arc_mean_matrix(s, [np.deg2rad(-5)], [np.deg2rad(5)])
    assert w[0] @ v == pytest.approx(0.75)


def test_mixture_arc_mean_matches_numeric():
    a, mu, sd = np.array([0.7, 0.3]), np.array([0.0, 0.3]), np.array([0.05, 0.1])
    lo, hi = np.array([-0.1, 0.2]), np.array([0.05, 0.5])
    got = mixture_arc_mean(a, mu, sd, lo, hi)
    for k in range(2):
        t = np.linspace(lo[k], hi[k], 100001)
        dens = (a * np.exp(-0.5 * ((t[:, None] - mu) / sd) ** 2) / (np.sqrt(2 * np.pi) * sd)).sum(1)
        assert got[k] == pytest.approx(dens.mean(), rel=1e-4)


def test_normalize_likelihood_unit_sum_floor_and_flat():
    p = normalize_likelihood([2.0, 3.0, 5.0, 2.0])
    assert p.sum() == pytest.approx(1.0) and np.all(p > 0)
    assert np.argmax(p) == 2
    assert np.allclose(normalize_likelihood(np.ones(5)), 0.2)


def test_wrong_length_detection_function_is_refused():
    with pytest.raises(ShapeError, match="detection function"):
        interpolate(AngularSampling.beams(36), np.ones(35), 0.0)
