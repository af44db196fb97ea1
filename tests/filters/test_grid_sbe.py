"""Grid sequential Bayesian estimation (Kushwaha 2010, Eqs. 28-31, 36-37)."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError, ShapeError
from fusetrack.filters.grid import (
    DirectionalMotion,
    GridSpec,
    GridTracker,
    SensorLikelihoods,
    fuse_product,
    fuse_weighted_sum,
    sbe_update,
)
from fusetrack.sensors.detection_function import (
    AngularSampling,
    arc_mean_matrix,
    cell_arcs,
    normalize_likelihood,
)


def test_grid_layout_matches_paper():
    g = GridSpec()
    assert g.shape == (70, 40) and g.size == 2800
    assert g.centres[0] == pytest.approx([0.25, 0.25])
    assert g.centres[1] == pytest.approx([0.25, 0.75])  # y index runs fastest
    with pytest.raises(ConfigError):
        GridSpec(x1=-1.0)


def test_motion_shifts_and_spreads_by_a_uniform_box():
    g = GridSpec(0, 10, 0, 10, 1.0)
    p = np.zeros(g.shape)
    p[2, 5] = 1.0
    out = DirectionalMotion(delta=1.0).predict(g, p.ravel(), v=[3.0, 0.0]).reshape(g.shape)
    # shifted 3 cells in x, then a 3x3 box: 1/9 on each of the 9 cells around (5, 5)
    assert out[4:7, 4:7] == pytest.approx(np.full((3, 3), 1 / 9))
    assert out.sum() == pytest.approx(1.0)
    half = DirectionalMotion(delta=0.0).predict(g, p.ravel(), v=[0.5, 0.0]).reshape(g.shape)
    assert half[2, 5] == pytest.approx(0.5) and half[3, 5] == pytest.approx(0.5)  # bilinear


def test_fusion_rules_hand_computed():
    lk = np.array([[0.1, 0.3, 0.6], [0.5, 0.25, 0.25]])
    prod = fuse_product(lk)
    assert prod == pytest.approx(np.array([0.05, 0.075, 0.15]) / 0.275)  # Eq. 30
    ws = fuse_weighted_sum(lk, [1.0, 3.0])
    assert ws == pytest.approx((1 * lk[0] + 3 * lk[1]) / 4)  # Eq. 31
    assert fuse_weighted_sum(lk, [0.0, 0.0]) == pytest.approx(np.full(3, 1 / 3))


def test_hybrid_product_with_prior_divided_equals_centralized():
    rng = np.random.default_rng(0)
    prior = rng.random(6)
    prior /= prior.sum()
    lik = SensorLikelihoods(rng.random((3, 6)), np.ones(3), ("audio", "audio", "video"))
    central = sbe_update(prior, lik, "product", "centralized")
    hybrid = sbe_update(prior, lik, "product", "hybrid", hybrid_divide_prior=True)
    assert hybrid == pytest.approx(central)
    double = sbe_update(prior, lik, "product", "hybrid")
    assert double == pytest.approx(central * prior / np.sum(central * prior))  # prior counted twice
    mixed = sbe_update(prior, lik, "sum", "hybrid", hybrid_alpha=1.0)
    audio_only = sbe_update(prior, lik.select(["audio"]), "sum", "centralized")
    assert mixed == pytest.approx(audio_only)
    with pytest.raises(ShapeError):
        SensorLikelihoods(np.ones((2, 6)), np.ones(3), ("audio", "video", "video"))


def test_tracker_follows_a_target_seen_by_bearing_sensors():
    g = GridSpec()
    sensors = [((5.0, 4.0), 0.3), ((30.0, 4.0), 2.0), ((17.5, 16.0), -1.0), ((17.5, 0.0), 1.5)]
    beams = AngularSampling.beams(36)
    mats = [arc_mean_matrix(beams, *cell_arcs(pos, h, g.centres, 0.25)[:2]) for pos, h in sensors]
    tracker = GridTracker(g, "product")
    errors = []
    for k in range(14):
        truth = np.array([2.0 + 2.5 * k, 8.5])
        rows = []
        for (pos, h), w in zip(sensors, mats):
            bearing = np.arctan2(truth[1] - pos[1], truth[0] - pos[0]) - h
            d = np.angle(np.exp(1j * (beams.angles - bearing)))
            lam = 1.0 + np.exp(-0.5 * (d / 0.3) ** 2)  # a beam pattern with a floor
            rows.append(normalize_likelihood(w @ lam))
        mean, cov = tracker.step(SensorLikelihoods(np.array(rows), np.ones(4), ("audio",) * 4))
        errors.append(np.linalg.norm(mean - truth))
        assert np.linalg.det(cov) > 0
    assert np.mean(errors[3:]) < 1.0
    assert np.linalg.norm(tracker.velocity - [2.5, 0.0]) < 1.0
