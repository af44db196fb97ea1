"""The timestamp CRLB of kushwaha2010-timesync (sync_bound): hand-computed cases, the generic
nuisance Schur complement, and least squares attaining it."""

import numpy as np
import pandas as pd
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.evaluation import gaussian_information
from fusetrack.experiments.kushwaha2010 import timesync
from fusetrack.experiments.kushwaha2010.scene import (
    default_layout,
    simulate_single_pass,
    stamp_trial,
)
from fusetrack.experiments.kushwaha2010.sync_bound import (
    chained_variance,
    hop_variance,
    map_information,
    map_value_variance,
)
from fusetrack.world.clocks import NodeClock, RbsDomain, fit_clock_map


def test_exact_regressors_give_the_least_squares_prediction_variance():
    # x = 0..3, x* = 5: sigma^2 (1/4 + (5 - 1.5)^2 / 5) = 2.7 sigma^2
    assert map_value_variance([0.0, 1.0, 2.0, 3.0], 1.0, 0.0, 4.0, 5.0) == pytest.approx(10.8)
    # two events, query at their mean: sigma^2 / 2 with sigma^2 = var_y + beta^2 var_x
    assert map_value_variance([0.0, 2.0], 2.0, 1.0, 1.0, 1.0) == pytest.approx(2.5)


def test_map_information_is_the_schur_complement_of_the_unknown_event_readings():
    x = np.array([0.3, 1.1, 2.0, 2.9, 4.2])
    beta, var = 1.3, 0.04
    K = x.size
    G = np.vstack([np.zeros((K, 2)), np.column_stack([np.ones(K), x])])  # d(s_x, s_y)/d(a, b)
    N = np.vstack([np.eye(K), beta * np.eye(K)])  # d(s_x, s_y)/d(x_k)
    generic = gaussian_information(G, var, nuisance=N)
    assert map_information(x, beta, var, var) == pytest.approx(generic, rel=1e-10)


def test_least_squares_attains_the_bound_with_exact_regressors():
    rng = np.random.default_rng(0)
    x = np.arange(8.0)
    sigma, query = 10e-6, 8.5
    a, b = 0.2, 1.00004
    pred = []
    for _ in range(4000):
        fa, fb = fit_clock_map(x, a + b * x + rng.normal(0, sigma, x.size))
        pred.append(fa + fb * query - (a + b * query))
    bound = map_value_variance(x, b, 0.0, sigma**2, query)
    assert np.var(pred) / bound == pytest.approx(1.0, abs=0.07)  # 4000 draws: s.e. 2.2 %


def test_rbs_attains_the_bound_with_jitter_on_both_receivers():
    """RBS's least squares (jitter on both receivers, 8 beacons) at a time after the window:
    its error variance over many independent beacon sets equals the errors-in-variables CRLB."""
    rng = np.random.default_rng(1)
    clocks = {"fusion": NodeClock(0.4, 30e-6), "cam": NodeClock(0.9, -45e-6)}
    t, errs, bounds = 7.6, [], []
    for _ in range(3000):
        rbs = RbsDomain(clocks, "fusion", rng)
        rbs.broadcast_until(8.0, 0.0)
        local = float(clocks["cam"].local(t))
        errs.append(rbs.to_reference("cam", local) - float(clocks["fusion"].local(t)))
        used = rbs.beacons_for("cam", local)
        beta = (1 + 30e-6) / (1 - 45e-6)
        x = clocks["cam"].local(rbs.beacons[used])
        bounds.append(map_value_variance(x, beta, rbs.jitter**2, rbs.jitter**2, local))
    assert np.mean(np.square(errs)) / np.mean(bounds) == pytest.approx(1.0, abs=0.08)


def test_hop_and_chained_variances():
    assert hop_variance(3, 5e-6) == pytest.approx(4 * 25e-12)
    with pytest.raises(ConfigError):
        hop_variance(0, 5e-6)
    # 1 through a slope-2 map, add 3, then a slope-0.5 map: ((1 * 4) + 3) * 0.25
    assert chained_variance([(1.0, 2.0), (3.0, 0.5)]) == pytest.approx(1.75)
    assert chained_variance([]) == 0.0
    with pytest.raises(ConfigError):
        map_information([1.0], 1.0, 1.0, 1.0)
    with pytest.raises(ConfigError):
        map_information([1.0, 2.0], 1.0, 0.0, 0.0)


def test_a_pass_keeps_each_packet_with_its_residual_and_bound():
    """Residuals and bounds follow the packets' arrival order (an acoustic packet's bound, with
    its hops and the gateway's map, is above every video packet's)."""
    sim = simulate_single_pass(default_layout(), np.random.default_rng(2))
    rec = sim.rec
    assert len(rec.sync_residuals) == len(rec.packets) == len(rec.sync_bounds)
    audio = np.array([p.sensor_id.startswith("A") for p in rec.packets])
    assert rec.sync_bounds[audio, 0].min() > rec.sync_bounds[~audio, 0].max()
    assert np.all(rec.sync_bounds[:, 1] <= rec.sync_bounds[:, 0] * (1 + 1e-9))
    res, bounds, is_audio = stamp_trial(default_layout(), np.random.default_rng(3))
    assert bounds[is_audio, 0].min() > bounds[~is_audio, 0].max()
    assert np.all(np.abs(res) < 1e-4)


def _claims(ms_ratio: float, rms: float):
    table = pd.DataFrame({"CRLB RMS, every beacon before (µs)": [10.0]}, index=["video (RBS)"])
    trials = pd.DataFrame(
        {
            "audio": [a for a in (True, False) for _ in range(400)],
            "ms": np.random.default_rng(0).chisquare(1, 800) * ms_ratio,
            "bound": np.ones(800),
        }
    )
    return timesync._sync_claims(table, {"video (RBS)": (rms, 0.5)}, trials)


def test_sync_claims_fail_for_a_bound_set_too_high_or_too_low():
    assert [c.holds for c in _claims(1.0, 11.0)] == [True, True]
    assert [c.holds for c in _claims(1.0, 8.0)] == [False, True]  # RMS below the causal bound
    assert not _claims(0.6, 11.0)[1].holds  # the bound too high: the protocol beats it
    assert not _claims(1.5, 11.0)[1].holds  # the bound too low: far from attained
