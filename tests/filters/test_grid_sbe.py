"""Grid sequential Bayesian estimation (Kushwaha 2010, Eqs. 28-31, 36-37)."""

import numpy as np
import pytest

from fusetrack.core import Filter, GridBelief, Measurement, SteppingFilter, filter_step
from fusetrack.core.errors import ConfigError, MeasurementError, ShapeError, UnknownSensorError
from fusetrack.filters.grid import (
    DirectionalMotion,
    GridFilter,
    GridSpec,
    SensorLikelihoods,
    fuse_product,
    fuse_weighted_sum,
    map_sensors,
    sbe_update,
)
from fusetrack.sensors.detection_function import (
    AngularSampling,
    arc_mean_matrix,
    cell_arcs,
    normalize_likelihood,
)
from fusetrack.sensors.likelihood_map import LikelihoodMapSensor


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


def _bearing_maps(g, sensors, mats, truth):
    """Per-cell likelihood maps of bearing sensors seeing ``truth`` (a beam pattern on a floor)."""
    beams = AngularSampling.beams(36)
    rows = []
    for (pos, h), w in zip(sensors, mats):
        bearing = np.arctan2(truth[1] - pos[1], truth[0] - pos[0]) - h
        d = np.angle(np.exp(1j * (beams.angles - bearing)))
        lam = 1.0 + np.exp(-0.5 * (d / 0.3) ** 2)
        rows.append(normalize_likelihood(w @ lam))
    return rows


def test_grid_filter_follows_a_target_seen_by_bearing_sensors():
    g = GridSpec()
    sensors = [((5.0, 4.0), 0.3), ((30.0, 4.0), 2.0), ((17.5, 16.0), -1.0), ((17.5, 0.0), 1.5)]
    beams = AngularSampling.beams(36)
    mats = [arc_mean_matrix(beams, *cell_arcs(pos, h, g.centres, 0.25)[:2]) for pos, h in sensors]
    ids = [f"A{i}" for i in range(4)]
    filt = GridFilter(g, map_sensors(g, ids, lambda _: "audio"), "product")
    assert isinstance(filt, Filter) and isinstance(filt, SteppingFilter)
    belief = filt.initial()
    assert isinstance(belief, GridBelief)
    errors = []
    for k in range(14):
        truth = np.array([2.0 + 2.5 * k, 8.5])
        rows = _bearing_maps(g, sensors, mats, truth)
        z = [Measurement(0.25 * k, sid, row) for sid, row in zip(ids, rows)]
        before = belief
        belief = filter_step(filt, belief, 0.25 if k else 0.0, z)
        assert before.updates == k  # the old belief is untouched: the filter is pure
        errors.append(np.linalg.norm(belief.mean - truth))
        assert np.linalg.det(belief.cov) > 0
    assert np.mean(errors[3:]) < 1.0
    assert np.linalg.norm(belief.velocity - [10.0, 0.0]) < 4.0  # 2.5 m per 0.25 s step


def test_grid_filter_step_is_predict_then_update_and_coasts():
    g = GridSpec(0, 10, 0, 10, 1.0)
    filt = GridFilter(g, map_sensors(g, ["a", "b"]), "product", motion=DirectionalMotion(1.0))
    rng = np.random.default_rng(2)
    b0 = filt.initial(rng.random(g.size))
    z = [Measurement(1.0, "a", rng.random(g.size)), Measurement(1.0, "b", rng.random(g.size))]
    b1 = filt.step(b0, 0.5, z)
    manual = filt.update(filt.predict(b0, 0.5), z)
    np.testing.assert_array_equal(b1.log_prob, manual.log_prob)
    expected = sbe_update(filt.predict(b0, 0.5).prob.ravel(), filt.likelihoods(z), "product")
    np.testing.assert_allclose(b1.prob.ravel(), expected, rtol=1e-12)
    b2 = filt.step(b1, 0.5, z)  # second posterior: the velocity is the mean's displacement / dt
    np.testing.assert_allclose(b2.velocity, (b2.mean - b1.mean) / 0.5, atol=1e-9)
    coast = filt.step(b2, 0.5, [])  # no measurement: the predicted density, velocity re-estimated
    np.testing.assert_allclose(coast.prob, filt.predict(b2, 0.5).prob, atol=1e-15)
    assert coast.updates == 3 and coast.elapsed == 0.0
    with pytest.raises(UnknownSensorError):
        filt.update(b0, [Measurement(0.0, "nobody", np.ones(g.size))])
    with pytest.raises(MeasurementError):
        filt.update(b0, [Measurement(0.0, "a", np.ones(3))])
    with pytest.raises(ShapeError):
        filt.initial(np.zeros(g.size))


def test_sum_fusion_uses_each_measurement_quality():
    g = GridSpec(0, 4, 0, 2, 1.0)
    filt = GridFilter(g, map_sensors(g, ["a", "b"]), "sum")
    la, lb = np.eye(g.size)[0] + 0.1, np.eye(g.size)[5] + 0.1
    z = [
        Measurement(0.0, "a", la, metadata={"quality": 1.0}),
        Measurement(0.0, "b", lb, metadata={"quality": 3.0}),
    ]
    post = filt.update(filt.initial(), z).prob.ravel()
    np.testing.assert_allclose(post, fuse_weighted_sum([la, lb], [1.0, 3.0]), rtol=1e-12)


def test_likelihood_map_sensor_reads_the_cell_of_each_state():
    g = GridSpec(0, 3, 0, 2, 1.0)  # cells centred at x 0.5, 1.5, 2.5 and y 0.5, 1.5
    s = LikelihoodMapSensor("m", (g.x, g.y))
    z = np.arange(1.0, 7.0)
    x = np.array([[0.4, 0.6], [2.6, 1.4], [1.5, 0.5], [9.0, -3.0]])  # the last is off the grid
    np.testing.assert_allclose(s.log_likelihood(z, x), np.log([1.0, 6.0, 3.0, 5.0]))
    assert s.log_likelihood(z, np.zeros((5, 7, 2))).shape == (5, 7)


def test_detection_quality_is_the_share_of_the_peak():
    from fusetrack.sensors.likelihood_map import detection_quality

    assert detection_quality([1.0, 1.0, 3.0, 1.0]) == 1.0  # all the excess in one sample
    assert detection_quality([0.0, 1.0, 2.0]) == pytest.approx(2 / 3)
    assert detection_quality(np.full(5, 4.0)) is None  # flat: the sensor saw nothing
