"""The track-oriented Poisson multi-Bernoulli filter (Williams 2015; issue 17): the Kalman and
extended Kalman filters when there is one certain target and nothing else, a hand-enumerated
scan, belief propagation against brute force, cardinality and GOSPA against the GM-PHD tracker
on a birth/death scenario, and bad input."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from fusetrack.core import (
    ConfigError,
    Gaussian,
    Measurement,
    MeasurementError,
    UnknownSensorError,
)
from fusetrack.evaluation import gospa
from fusetrack.filters import ExtendedKalmanFilter, GMPHDFilter, KalmanFilter, PhdIntensity
from fusetrack.motion import ConstantVelocity, LinearGaussianMotion
from fusetrack.sensors import LinearGaussianSensor, RangeBearing
from fusetrack.tracking import (
    PHDTracker,
    PMBDensity,
    PMBFilter,
    PMBTracker,
    Tracker,
    cardinality_distribution,
)

H_POS = np.hstack([np.eye(2), np.zeros((2, 2))])
MOTION = ConstantVelocity(ndim=2, q=0.05)
NOTHING = PhdIntensity.empty(4)


def _one_bernoulli(r, mean, cov, undetected=None):
    d = len(mean)
    return PMBDensity(
        PhdIntensity.empty(d) if undetected is None else undetected,
        PhdIntensity([r], [mean], [cov], [7], 8),
    )


# (1) one certain target, P_D = 1, no clutter, no births: the Kalman filter ----------------------


@pytest.mark.parametrize("kind", ["kalman", "ekf"])
def test_one_certain_target_without_clutter_is_the_kalman_filter(kind):
    if kind == "kalman":
        sensor = LinearGaussianSensor("s", H=H_POS, R=0.25 * np.eye(2))
        filt = KalmanFilter(MOTION, [sensor])
    else:
        sensor = RangeBearing("s", position=[0.0, -30.0], sigma_range=0.5, sigma_bearing=0.02)
        filt = ExtendedKalmanFilter(MOTION, [sensor])
    pmb = PMBFilter(MOTION, [sensor], NOTHING, survival_probability=1.0, detection_probability=1.0)
    prior = Gaussian(np.array([0.0, 0.0, 1.0, 0.5]), np.diag([4.0, 4.0, 1.0, 1.0]))
    density, g = _one_bernoulli(1.0, prior.mean, prior.cov), prior
    rng = np.random.default_rng(1)
    x = np.array([0.5, -0.3, 1.0, 0.5])
    for k in range(1, 16):
        x = MOTION.sample(x, 1.0, rng)
        z = Measurement(float(k), "s", sensor.simulate(x, rng))
        density = pmb.update(pmb.predict(density, 1.0), [z])
        g = filt.update(filt.predict(g, 1.0), [z])
        assert density.existence.tolist() == pytest.approx([1.0], abs=1e-10)
        np.testing.assert_allclose(density.tracks.means[0], g.mean, rtol=0, atol=1e-10)
        np.testing.assert_allclose(density.tracks.covs[0], g.cov, rtol=0, atol=1e-10)
    assert density.tracks.labels.tolist() == [7]  # no Bernoulli born (no clutter, no Poisson)


# (2) one Bernoulli, two measurements, a Poisson component: by hand -----------------------------


def _npdf(z, m, v):
    return np.exp(-0.5 * (z - m) ** 2 / v) / np.sqrt(2 * np.pi * v)


def test_one_scan_one_bernoulli_two_measurements_by_exact_enumeration():
    motion = LinearGaussianMotion(F=[[1.0]], Q=[[0.1]])
    sensor = LinearGaussianSensor("s", H=[[1.0]], R=[[0.5]])
    r, m, p = 0.8, 0.0, 2.0  # the Bernoulli
    w_u, m_u, p_u = 0.3, 3.0, 4.0  # the Poisson (undetected) intensity: one component
    pd, kappa = 0.9, 0.02
    z1, z2 = 0.4, 2.5
    pmb = PMBFilter(motion, [sensor], NOTHING.__class__.empty(1),
                    detection_probability=pd, clutter_intensity=kappa)  # fmt: skip
    prior = _one_bernoulli(r, [m], [[p]], PhdIntensity([w_u], [[m_u]], [[[p_u]]]))
    post = pmb.update(prior, [Measurement(0.0, "s", [z1]), Measurement(0.0, "s", [z2])])

    # by hand: hypothesis weights, then every joint event enumerated
    s = p + 0.5
    w_miss = 1 - r * pd
    w_hit = [r * pd * _npdf(z, m, s) for z in (z1, z2)]
    born = [pd * w_u * _npdf(z, m_u, p_u + 0.5) for z in (z1, z2)]
    e = [kappa + b for b in born]
    events = {"miss": w_miss * e[0] * e[1], "z1": w_hit[0] * e[1], "z2": w_hit[1] * e[0]}
    total = sum(events.values())
    beta = {k: v / total for k, v in events.items()}
    beta_row = pmb.marginals(np.log([w_hit]), np.log([w_miss]), np.log(e))[0]
    np.testing.assert_allclose(beta_row, [beta["z1"], beta["z2"], beta["miss"]], atol=1e-12)

    r_miss = r * (1 - pd) / (1 - r * pd)
    r_post = beta["miss"] * r_miss + beta["z1"] + beta["z2"]
    k = p / s
    means = [m, m + k * (z1 - m), m + k * (z2 - m)]
    w = np.array([beta["miss"] * r_miss, beta["z1"], beta["z2"]]) / r_post
    mean = w @ means
    var = w @ (np.array([p, (1 - k) * p, (1 - k) * p]) + (np.array(means) - mean) ** 2)
    new_r = [(1 - beta["z1"]) * born[0] / e[0], (1 - beta["z2"]) * born[1] / e[1]]
    k_u = p_u / (p_u + 0.5)
    new_means = [m_u + k_u * (z - m_u) for z in (z1, z2)]

    assert post.tracks.labels.tolist() == [7, 8, 9]  # the old Bernoulli, then z1's and z2's
    np.testing.assert_allclose(post.existence, [r_post, *new_r], rtol=1e-12)
    np.testing.assert_allclose(post.tracks.means[:, 0], [mean, *new_means], rtol=1e-12)
    np.testing.assert_allclose(
        post.tracks.covs[:, 0, 0], [var, (1 - k_u) * p_u, (1 - k_u) * p_u], rtol=1e-12
    )
    assert post.origins == {8: (0.0, "s", 0), 9: (0.0, "s", 1)}
    np.testing.assert_allclose(post.undetected.weights, [(1 - pd) * w_u])  # missed: scaled
    assert 0.0 < post.existence[1] < 0.5 < post.existence[0]  # z1 is the track's, z2 is new


# (3) loopy belief propagation against brute force ----------------------------------------------


def _brute_force(log_hit, log_miss, log_new):
    """Every joint event: each track a measurement or missed, each measurement at most once;
    a measurement no track took has weight e_j."""
    n, m = log_hit.shape
    beta, total = np.zeros((n, m + 1)), 0.0
    for event in itertools.product(range(m + 1), repeat=n):
        taken = [j for j in event if j < m]
        if len(taken) != len(set(taken)):
            continue
        logp = sum(log_hit[i, j] if j < m else log_miss[i] for i, j in enumerate(event))
        logp += sum(log_new[j] for j in range(m) if j not in taken)
        w = np.exp(logp)
        total += w
        for i, j in enumerate(event):
            beta[i, j] += w
    return beta / total


def test_belief_propagation_marginals_are_close_to_brute_force_on_small_problems():
    rng = np.random.default_rng(4)
    bp = PMBFilter(MOTION, [LinearGaussianSensor("s", H=H_POS, R=np.eye(2))], NOTHING)
    exact = PMBFilter(MOTION, [LinearGaussianSensor("s", H=H_POS, R=np.eye(2))], NOTHING,
                      max_exact_events=10**6)  # fmt: skip
    errors = []
    for _ in range(30):
        r = rng.uniform(0.3, 1.0, 3)
        log_hit = np.log(r[:, None] * 0.9 * rng.exponential(1.0, (3, 4)))
        log_miss, log_new = np.log1p(-0.9 * r), np.log(rng.uniform(0.2, 2.0, 4))
        truth = _brute_force(log_hit, log_miss, log_new)
        np.testing.assert_allclose(exact.marginals(log_hit, log_miss, log_new), truth, atol=1e-10)
        approx = bp.marginals(log_hit, log_miss, log_new)
        np.testing.assert_allclose(approx.sum(axis=1), 1.0)
        assert np.all(approx[:, :-1].sum(axis=0) <= 1.0 + 1e-9)  # "new" marginals >= 0
        errors.append(np.abs(approx - truth).mean())
    assert np.mean(errors) < 0.02
    assert max(errors) > 1e-4  # a loopy graph: the approximation is not exact


def test_map_cardinality_of_independent_bernoullis():
    np.testing.assert_allclose(
        cardinality_distribution(np.array([0.5, 0.2])), [0.4, 0.5, 0.1]
    )  # (0.5 + 0.5x)(0.8 + 0.2x)
    r = np.array([0.1, 0.45, 0.9, 0.45])
    # (0.1 + 0.9x)(0.55 + 0.45x)^2(0.9 + 0.1x), expanded by hand
    by_hand = [0.027225, 0.2926, 0.45135, 0.2106, 0.018225]
    np.testing.assert_allclose(cardinality_distribution(r), by_hand, atol=1e-12)
    density = PMBDensity(NOTHING, PhdIntensity(r, np.zeros((4, 4)), np.tile(np.eye(4), (4, 1, 1))))
    pmb = PMBFilter(MOTION, [POS], NOTHING)
    assert PMBTracker(pmb).extracted(density).tolist() == [2]  # r > 0.5
    assert PMBTracker(pmb, extraction="map").extracted(density).tolist() == [2, 1]  # n = 2


# (4) birth and death in clutter: cardinality, GOSPA against the GM-PHD tracker -----------------

SIDE, CLUTTER, PD, SCANS, SIGMA = 200.0, 5.0, 0.9, 40, 1.0
LIVES = [(0, 40), (3, 25), (8, 40), (15, 35), (20, 40)]  # [born, dies) of each target
POS = LinearGaussianSensor("pos", H=H_POS, R=SIGMA**2 * np.eye(2))
BIRTH = PhdIntensity([0.05], [[SIDE / 2, SIDE / 2, 0, 0]], [np.diag([80.0**2] * 2 + [2.0**2] * 2)])
SETTINGS = {"survival_probability": 0.99, "detection_probability": PD,
            "clutter_intensity": CLUTTER / SIDE**2}  # fmt: skip


def _birth_death(seed):
    rng = np.random.default_rng(seed)
    n = len(LIVES)
    x = np.column_stack([rng.uniform(40, 160, (n, 2)), rng.normal(0.0, 1.0, (n, 2))])
    truth, scans = [], []
    for k in range(SCANS):
        if k:
            x = MOTION.sample(x, 1.0, rng)
        alive = [i for i, (a, b) in enumerate(LIVES) if a <= k < b]
        truth.append(x[alive, :2].copy())
        zs = [Measurement(float(k), "pos", x[i, :2] + SIGMA * rng.standard_normal(2))
              for i in alive if rng.random() < PD]  # fmt: skip
        zs += [Measurement(float(k), "pos", rng.uniform(0, SIDE, 2))
               for _ in range(rng.poisson(CLUTTER))]  # fmt: skip
        scans.append(zs)
    return scans, truth


def _estimates(tracker, scans):
    state, out, ids = tracker.initial_state(), [], set()
    for k, zs in enumerate(scans):
        state = tracker.step(state, float(k), zs)
        out.append(np.array([t.belief.mean[:2] for t in state.confirmed]).reshape(-1, 2))
        ids.update(t.id for t in state.confirmed)
    return out, ids


def test_birth_death_cardinality_and_gospa_beat_the_gm_phd_tracker():
    """Measured (seeds 0-2, scans 5-39, GOSPA c = 10 m, p = 2): PMB 3.10, 3.09, 3.03 m; GM-PHD
    4.18, 4.20, 3.89 m; mean count error -0.09, -0.09, -0.09 (PHD -0.37, -0.34, -0.37)."""
    for seed in range(3):
        scans, truth = _birth_death(seed)
        pmb_tracker = PMBTracker(PMBFilter(MOTION, [POS], BIRTH, **SETTINGS))
        assert isinstance(pmb_tracker, Tracker)
        pmb, ids = _estimates(pmb_tracker, scans)
        phd, _ = _estimates(PHDTracker(GMPHDFilter(MOTION, [POS], BIRTH, **SETTINGS)), scans)
        count_error = np.mean([len(e) - len(t) for e, t in zip(pmb[5:], truth[5:])])
        assert abs(count_error) < 0.2
        g_pmb = np.mean([gospa(e, t, c=10.0).distance for e, t in zip(pmb[5:], truth[5:])])
        g_phd = np.mean([gospa(e, t, c=10.0).distance for e, t in zip(phd[5:], truth[5:])])
        assert g_pmb < g_phd - 0.5
        assert len(ids) <= len(LIVES) + 1  # persistent ids: at most one broken track


# (5) bad input ----------------------------------------------------------------------------------


def _tracking_one():
    tr = PMBTracker(PMBFilter(MOTION, [POS], BIRTH, **SETTINGS))
    state = tr.initial_state()
    for k in range(3):
        state = tr.step(state, float(k), [Measurement(float(k), "pos", [50.0 + k, 50.0])])
    assert [t.id for t in state.confirmed] == [0]
    return tr, state


def test_nan_reports_are_counted_and_skipped_unknown_sensors_raise_before_any_work():
    tr, state = _tracking_one()
    nan = Measurement(3.0, "pos", [np.nan, 50.0])
    after = tr.step(state, 3.0, [nan, Measurement(3.0, "pos", [54.0, 51.0])])
    assert tr.filter.stats.skipped_measurements == 1
    assert [t.id for t in after.confirmed] == [0]
    predicted = tr.filter.predict(state.density, 1.0).tracks.means[0, :2]  # (52.8, 50.0)
    assert np.all(after.confirmed[0].belief.mean[:2] - predicted > 0.5)  # z = (54, 51) was used
    missed = tr.step(state, 3.0, [nan])  # only a NaN: the sensor looked and saw nothing
    assert tr.filter.stats.skipped_measurements == 2
    assert [t.id for t in missed.confirmed] == [0]  # an existence of 1 survives a miss
    with pytest.raises(UnknownSensorError, match="radar"):
        tr.step(
            state, 3.0, [Measurement(3.0, "pos", [53.0, 50.0]), Measurement(3.0, "radar", [1.0])]
        )
    with pytest.raises(MeasurementError, match="value"):
        tr.step(state, 3.0, [Measurement(3.0, "pos", [53.0, 50.0, 1.0])])
    assert tr.filter.stats.skipped_measurements == 2


def test_bad_configuration_is_a_clear_error():
    pmb = PMBFilter(MOTION, [POS], BIRTH, **SETTINGS)
    with pytest.raises(ConfigError, match="extraction"):
        PMBTracker(pmb, extraction="mode")
    with pytest.raises(ConfigError, match="PMBFilter"):
        PMBTracker(GMPHDFilter(MOTION, [POS], BIRTH))  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="existence_threshold"):
        PMBFilter(MOTION, [POS], BIRTH, existence_threshold=1.5)
    with pytest.raises(ConfigError, match="PMBDensity"):
        pmb.predict(PhdIntensity.empty(4), 1.0)  # type: ignore[arg-type]
