"""Kushwaha 2010 Ch. IV: ML fundamentals, the Eq. 56 beamform model, Gibbs + slice sampling, EBL."""

import numpy as np
import pytest

from fusetrack.core.slice_sampling import slice_sample
from fusetrack.perception.harmonic_features import (
    CompressedPsd,
    NodeFeatures,
    beamform,
    compress_psd,
    harmonicity,
    node_features,
    psd,
)
from fusetrack.perception.source_localisation.energy import energy_localise
from fusetrack.perception.source_localisation.harmonic import BeamformModel, localise, match_error
from fusetrack.perception.source_localisation.harmonic_beamform import (
    AcousticNetwork,
    SourceBeamform,
    fit_gain_offset,
    source_beamform,
)
from fusetrack.perception.source_localisation.harmonic_frequencies import (
    estimate_frequencies,
    psd_neg_log_likelihood,
)
from fusetrack.world.harmonic_sources import (
    HarmonicSource,
    noise_sigma,
    random_sources,
    received_signals,
)

SENSORS = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0], [0.0, 5.0]])
FS = 100e3


def _features(sources, net, rng, snr_db=25.0, n=100_000):
    x = received_signals(sources, net.microphones().reshape(-1, 2), n, rng, fs=FS)
    x = x + noise_sigma(x, snr_db) * rng.standard_normal(x.shape)
    x = x.reshape(net.n_sensors, net.array.n_mics, n)
    return [node_features(x[k], net.array, c=net.c) for k in range(net.n_sensors)]


def _one_mic_psd(f0, rng, snr_db=25.0):
    src = random_sources(1, rng, avoid=SENSORS, f0s=[f0], positions=[[3.0, 2.0]])
    x = received_signals(src, np.array([[0.0, 0.0]]), 100_000, rng, fs=FS)[0]
    x = x + noise_sigma(x, snr_db) * rng.standard_normal(x.size)
    return compress_psd(*psd(x, FS, 4000.0, 4000), 30)


def test_ml_fundamental_of_a_harmonic_signal_within_0p1_hz():
    rng = np.random.default_rng(3)
    for f0 in (47.31, 83.77, 131.05):
        p = _one_mic_psd(f0, rng)
        raw = estimate_frequencies([p], 1, rng, refine=False).f0[0]
        fine = estimate_frequencies([p], 1, rng).f0[0]
        assert abs(raw - f0) < 0.1  # Eq. 46 on 1 Hz bins, harmonics up to 1 kHz
        assert abs(fine - f0) < 0.01  # with the sub-bin line fit


def test_psd_likelihood_is_least_at_the_truth_not_at_a_subharmonic():
    rng = np.random.default_rng(4)
    f0 = 61.4
    p = _one_mic_psd(f0, rng)
    truth = float(psd_neg_log_likelihood([f0], [p]))
    for wrong in (f0 / 2, f0 / 3, f0 + 0.5, f0 - 0.5, 2 * f0):
        assert float(psd_neg_log_likelihood([wrong], [p])) > truth


def test_beamform_model_matches_a_simulated_two_source_beamform():
    """Eq. 56 with the true harmonic powers reproduces the delay-and-sum beam energies: gain 1,
    offset 0 and a residual below 2% of the pattern's spread (noise-free, 1 s window)."""
    rng = np.random.default_rng(5)
    net = AcousticNetwork(SENSORS, headings=np.array([0.0, 0.7, -2.0, 3.0]))
    srcs = random_sources(
        2, rng, avoid=SENSORS, f0s=[57.3, 96.1], positions=[[2.5, 1.5], [7.0, 3.8]]
    )
    mics = net.microphones()
    x = received_signals(srcs, mics.reshape(-1, 2), 100_000, rng, fs=FS).reshape(4, 4, -1)
    total = np.zeros((4, 36))
    for s in srcs:
        lam2 = (1.0 / np.hypot(*(net.positions - s.position).T)) ** 2  # λ_k² at the node centres
        powers = lam2[:, None] * s.energies[None, :]
        freqs = np.broadcast_to(s.frequencies, powers.shape)
        total += SourceBeamform(net, powers, freqs)(s.position)
    for k in range(4):
        b = beamform(x[k], net.array, fs=FS, c=net.c, length=100_000 - 64)
        a, c, rss = fit_gain_offset(b[None], total[k][None])
        assert a[0] == pytest.approx(1.0, rel=0.03)
        assert abs(c[0]) < 0.03 * b.mean()
        assert np.sqrt(rss[0] / 36) < 0.02 * b.std()
    # a source put 1.5 m away fits clearly worse at the sensors that see it move
    s = srcs[0]
    lam2 = (1.0 / np.hypot(*(net.positions - s.position).T)) ** 2
    powers = lam2[:, None] * s.energies[None, :]
    freqs = np.broadcast_to(s.frequencies, powers.shape)
    right = SourceBeamform(net, powers, freqs)(s.position)
    wrong = SourceBeamform(net, powers, freqs)(s.position + np.array([0.0, 1.5]))
    assert np.abs(right - wrong).max() > 0.05 * right.std()


def test_precomputed_source_beamform_equals_the_reference():
    rng = np.random.default_rng(6)
    net = AcousticNetwork(SENSORS, headings=np.array([0.0, 1.0, 2.0, 3.0]))
    A = rng.random((4, 12))
    A[:, 3] = 0.0
    F = rng.uniform(50, 1000, (4, 12))
    x = rng.uniform(0, 5, (5, 3, 2))
    np.testing.assert_allclose(
        SourceBeamform(net, A, F)(x), source_beamform(net, x, A, F), atol=1e-9
    )


def test_slice_sampler_draws_a_standard_normal():
    rng = np.random.default_rng(7)
    x, draws = 3.0, []
    for _ in range(4000):
        x = slice_sample(lambda v: -0.5 * v * v, x, rng, width=1.0).x
        draws.append(x)
    d = np.array(draws[200:])
    assert abs(d.mean()) < 0.1
    assert d.var() == pytest.approx(1.0, abs=0.12)
    # bounded support is respected
    y = [slice_sample(lambda v: 0.0, 0.5, rng, lower=0.0, upper=1.0).x for _ in range(300)]
    assert min(y) >= 0.0 and max(y) <= 1.0 and np.mean(y) == pytest.approx(0.5, abs=0.06)


def test_two_sources_located_and_separated():
    rng = np.random.default_rng(8)
    net = AcousticNetwork(SENSORS)
    srcs = random_sources(
        2, rng, avoid=SENSORS, f0s=[71.3, 118.6], positions=[[2.5, 1.5], [7.5, 3.5]]
    )
    res = localise(net, _features(srcs, net, rng), 2, rng, model=BeamformModel(n_samples=20))
    err, perm = match_error(res.positions, [s.position for s in srcs])
    assert err < 0.3
    np.testing.assert_allclose(res.f0[perm], [71.3, 118.6], atol=0.05)
    assert res.supported.all() and res.harmonicity > 0.8


def test_more_sources_requested_than_present_and_no_harmonic_peaks():
    rng = np.random.default_rng(9)
    net = AcousticNetwork(SENSORS)
    src = random_sources(1, rng, avoid=SENSORS, f0s=[88.8], positions=[[4.0, 2.0]])
    feats = _features(src, net, rng)
    res = localise(net, feats, 2, rng, model=BeamformModel(n_samples=10))
    assert np.all(np.isfinite(res.positions)) and np.all(np.isfinite(res.f0))
    good = int(np.argmin(np.abs(res.f0 - 88.8)))
    assert abs(res.f0[good] - 88.8) < 0.05
    assert np.hypot(*(res.positions[good] - [4.0, 2.0])) < 0.3
    # a PSD with no peaks at all: every source unsupported, nothing NaN
    empty = [NodeFeatures(f.beamform, CompressedPsd(np.zeros(0), np.zeros(0))) for f in feats]
    res0 = localise(net, empty, 2, rng, model=BeamformModel(n_samples=5))
    assert not res0.supported.any()
    assert np.all(np.isfinite(res0.positions)) and np.isfinite(res0.neg_log_posterior)
    assert res0.harmonicity == 0.0
    # white noise only: low harmonicity (Eq. 59), still finite
    noise = rng.standard_normal(100_000)
    p = compress_psd(*psd(noise, FS, 4000.0, 4000), 30)
    f0 = estimate_frequencies([p], 1, rng, n_samples=5).f0
    assert np.isfinite(f0).all() and harmonicity(p.freqs, p.powers, f0) < 0.5


def test_energy_localisation_recovers_a_source_from_exact_energies():
    truth = np.array([3.3, 1.7])
    y = 5.0 / np.sum((SENSORS - truth) ** 2, axis=1)
    X, S = energy_localise(y, SENSORS, grid_step=0.1)
    assert np.hypot(*(X[0] - truth)) < 0.08
    assert S[0] == pytest.approx(5.0, rel=0.1)
    ring = np.array(
        [[np.cos(a) * 6 + 5, np.sin(a) * 4 + 2.5] for a in np.linspace(0, 6.28, 8, endpoint=False)]
    )
    two = np.array([[2.0, 2.0], [8.0, 3.0]])
    y2 = sum(s / np.sum((ring - t) ** 2, axis=1) for s, t in zip((3.0, 6.0), two, strict=True))
    X2, _ = energy_localise(y2, ring, 2, field_box=(0, 10, 0, 5), grid_step=0.1)
    assert match_error(X2, two)[0] < 0.1


def test_match_error_uses_the_best_assignment():
    err, perm = match_error([[1.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [1.0, 0.5]])
    assert err == pytest.approx(0.25) and list(perm) == [1, 0]


def test_harmonic_source_checks_and_directivity():
    with pytest.raises(ValueError, match="f0"):
        HarmonicSource(np.zeros(2), -1.0, np.ones(3))
    s = HarmonicSource(np.zeros(2), 50.0, np.ones(3), facing=0.0, directivity=1.0)
    g = s.gain(np.array([[2.0, 0.0], [-2.0, 0.0]]))
    assert g[0] == pytest.approx(0.5) and g[1] == pytest.approx(0.5 / 3)  # ((2 + cos φ)/3)^β / r


def test_factorised_powers_fill_a_harmonic_a_node_did_not_send():
    from fusetrack.perception.source_localisation.harmonic_frequencies import factorised_powers

    f0 = np.array([50.0])
    lam2 = np.array([1.0, 0.25, 4.0])
    psi = np.array([8.0, 4.0, 2.0, 1.0])
    full = lam2[:, None] * psi[None, :]  # (K, H)
    powers = full[:, None, :].copy()  # (K, M=1, J=H): peak j is harmonic j + 1
    freqs = np.broadcast_to(f0[0] * np.arange(1, 5), powers.shape).copy()
    powers[1, 0, 2] = 0.0  # node 1 did not send harmonic 3
    filled, grid = factorised_powers(f0, powers, freqs)
    np.testing.assert_allclose(filled[:, 0, :], full, rtol=1e-6)
    np.testing.assert_allclose(grid[0, 0], [50.0, 100.0, 150.0, 200.0])


def test_range_aware_powers_follow_the_hypothesised_ranges():
    """A-IV-7's source-level variant: with PSD powers that decay as 1/r² from the source, the
    range-aware share at the true position is the exact Eq. 56 share; elsewhere its levels follow
    the ranges from the hypothesised position, not the PSD's."""
    from fusetrack.perception.source_localisation.harmonic import _Posterior

    rng = np.random.default_rng(10)
    net = AcousticNetwork(SENSORS)
    (s,) = random_sources(1, rng, avoid=SENSORS, f0s=[83.0], positions=[[3.0, 1.5]])
    lam2 = 1.0 / np.hypot(*(net.positions - s.position).T) ** 2
    powers = (lam2[:, None] * s.energies[None, :])[:, None, :]  # (K, M=1, H)
    freqs = np.broadcast_to(s.frequencies, powers.shape)
    B = np.ones((4, 36))
    ranged = _Posterior(net, B, powers, freqs, BeamformModel(powers="range-aware"), None)
    fixed = _Posterior(net, B, powers, freqs, BeamformModel(), None)
    np.testing.assert_allclose(ranged.share(0, s.position), fixed.share(0, s.position), rtol=1e-9)
    elsewhere = np.array([8.0, 4.0])
    r2 = np.hypot(*(net.positions - elsewhere).T) ** 2
    # ranged / fixed at node k = L / r_k(elsewhere)² / λ_k² (fixed keeps the PSD's λ_k²)
    per_node = ranged.share(0, elsewhere).mean(-1) / fixed.share(0, elsewhere).mean(-1)
    level = per_node * r2 * lam2
    np.testing.assert_allclose(level / level[0], 1.0, rtol=1e-9)
    assert np.ptp(per_node) > 0.5 * per_node.max()


def test_range_aware_localises_two_sources_without_directivity():
    rng = np.random.default_rng(8)
    net = AcousticNetwork(SENSORS)
    srcs = random_sources(
        2, rng, avoid=SENSORS, f0s=[71.3, 118.6], positions=[[2.5, 1.5], [7.5, 3.5]]
    )
    feats = _features(srcs, net, rng)
    first = localise(net, feats, 2, rng, model=BeamformModel(n_samples=20))
    model = BeamformModel(n_samples=20, powers="range-aware")
    res = localise(net, feats, 2, rng, model=model, f0_init=first.f0, start=first.positions)
    assert match_error(res.positions, [s.position for s in srcs])[0] < 0.3
