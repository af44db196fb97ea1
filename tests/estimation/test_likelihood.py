"""log_likelihood: the whole-run kernels give the filters' own numbers, and the particle
estimate behaves as the theory says against the Kalman filter's exact value."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _estimation_models import THETA, kalman_model, particle_model, parts, simulate

from fusetrack.core import (
    ConfigError,
    DegenerateWeightsWarning,
    Gaussian,
    Measurement,
    MeasurementError,
)
from fusetrack.estimation import LogLikelihood, log_likelihood
from fusetrack.filters import (
    BootstrapFilter,
    KalmanFilter,
    RegularizedParticleFilter,
    run_filter,
)
from fusetrack.motion import ConstantVelocity, LinearGaussianMotion
from fusetrack.sensors import LinearGaussianSensor

ZS = simulate(100, seed=3)


def _run_filter_ll(filt, prior, zs, rng=None, t0=None) -> float:
    return float(
        run_filter(filt, prior, zs, rng=rng, t0=t0, log_likelihood=True).info["log_likelihood"]
    )


def test_kalman_kernel_is_the_kalman_filters_value():
    kf, prior = kalman_model(THETA)
    ev = LogLikelihood(ZS)
    assert ev.path(kf, prior) == "kalman kernel"
    assert ev(kf, prior) == pytest.approx(_run_filter_ll(kf, prior, ZS), rel=1e-12)


def test_kalman_by_hand():
    """Random walk, q = 0.5, r = 1, prior N(0, 1): every innovation variance is 2."""
    kf = KalmanFilter(
        LinearGaussianMotion(F=[[1.0]], Q=[[0.5]]),
        [LinearGaussianSensor("s", H=[[1.0]], R=[[1.0]])],
    )
    zs = [Measurement(float(t), "s", [z]) for t, z in enumerate([0.1, 0.4, -0.2])]
    innovations = [0.1, 0.4 - 0.05, -0.2 - 0.225]  # means 0, 0.05, 0.225 by K = 1/2
    want = sum(-0.5 * math.log(2 * math.pi * 2) - y * y / 4 for y in innovations)
    assert log_likelihood(kf, Gaussian(np.zeros(1), np.eye(1)), zs) == pytest.approx(
        want, abs=1e-12
    )


@pytest.mark.parametrize(("seed", "ess"), [(0, 1.0), (1, 1.0), (2, 0.5), (3, 0.0)])
def test_bootstrap_kernel_draws_what_the_filter_draws(seed, ess):
    """The same estimate for a seed, whether every step resamples (ESS threshold 1), some do
    (0.5: weights carried over between resamplings) or none (0)."""
    motion, sensor, prior = parts(THETA)
    pf = BootstrapFilter(motion, [sensor], n_particles=300, ess_threshold=ess)
    ev = LogLikelihood(ZS, t0=-1.0)
    assert ev.path(pf, prior) == "bootstrap kernel"
    fast = ev(pf, prior, np.random.default_rng(seed))
    slow = _run_filter_ll(pf, prior, ZS, np.random.default_rng(seed), t0=-1.0)
    assert fast == pytest.approx(slow, abs=1e-9)


def _two_sensor_series(seed: int) -> list[Measurement]:
    """Irregular times; sensor "b" (2-D, correlated noise) reports with "a" every third step."""
    rng = np.random.default_rng(seed)
    ms, t = [], 0.0
    for k in range(40):
        t += rng.uniform(0.2, 1.5)
        ms.append(Measurement(t, "a", rng.normal(size=1)))
        if k % 3 == 0:
            ms.append(Measurement(t, "b", rng.normal(size=2)))
    return ms


def test_kernels_on_several_sensors_and_irregular_steps():
    cv = ConstantVelocity(ndim=1, q=0.3)
    a = LinearGaussianSensor("a", H=[[1.0, 0.0]], R=[[0.4]])
    b = LinearGaussianSensor("b", H=[[1.0, 0.0], [0.0, 1.0]], R=[[0.5, 0.1], [0.1, 0.3]])
    ms, prior = _two_sensor_series(5), Gaussian(np.zeros(2), np.eye(2))
    ev = LogLikelihood(ms)
    kf, pf = KalmanFilter(cv, [a, b]), BootstrapFilter(cv, [a, b], n_particles=200)
    assert ev(kf, prior) == pytest.approx(_run_filter_ll(kf, prior, ms), rel=1e-12)
    fast = ev(pf, prior, np.random.default_rng(7))
    assert fast == pytest.approx(_run_filter_ll(pf, prior, ms, np.random.default_rng(7)), abs=1e-9)


def test_a_single_step_series():
    """Two reports at one time, no prediction: the prior weighed by both."""
    zs = [Measurement(2.0, "y", [0.3]), Measurement(2.0, "y", [-0.1])]
    (kf, prior), (pf, _) = kalman_model(THETA), particle_model(200)(THETA)
    ev = LogLikelihood(zs)
    assert ev(kf, prior) == pytest.approx(_run_filter_ll(kf, prior, zs), rel=1e-12)
    fast = ev(pf, prior, np.random.default_rng(0))
    assert fast == pytest.approx(_run_filter_ll(pf, prior, zs, np.random.default_rng(0)), abs=1e-12)


def test_other_filters_take_the_generic_loop():
    motion, sensor, prior = parts(THETA)
    for filt in (
        RegularizedParticleFilter(motion, [sensor], n_particles=100),
        BootstrapFilter(motion, [sensor], n_particles=100, resampler="stratified"),
    ):
        ev = LogLikelihood(ZS)
        assert ev.path(filt, prior) == "run_filter"
        got = ev(filt, prior, np.random.default_rng(1))
        assert got == _run_filter_ll(filt, prior, ZS, np.random.default_rng(1))


def test_a_batch_is_each_model_alone():
    ev = LogLikelihood(ZS)
    thetas = [THETA, THETA + 0.3, THETA - 0.2]
    models = [particle_model(200)(th) for th in thetas] + [kalman_model(THETA)]
    for threads in (False, True):
        gens = np.random.default_rng(4).spawn(4)
        alone = [ev(f, p, g) for (f, p), g in zip(models, np.random.default_rng(4).spawn(4))]
        assert ev.many(models, gens, threads=threads) == pytest.approx(alone, abs=1e-12)


def test_particle_estimate_against_the_exact_value():
    """The likelihood estimate is unbiased (Del Moral 2004): mean(exp(ll - ll_exact)) = 1; its
    log is biased by about -Var/2 (delta method) and its variance falls as 1/N."""
    ev = LogLikelihood(ZS)
    exact = ev(*kalman_model(THETA))
    runs = {}
    for n in (250, 1000):
        pf, prior = particle_model(n)(THETA)
        gens = np.random.default_rng(n).spawn(300)
        runs[n] = np.array([ev(pf, prior, g) for g in gens])
    for n, ll in runs.items():
        ratio = np.exp(ll - exact)
        assert abs(ratio.mean() - 1.0) < 3.5 * ratio.std(ddof=1) / math.sqrt(ll.size), n
        var = ll.var(ddof=1)
        bias_se = ll.std(ddof=1) / math.sqrt(ll.size)
        assert abs(ll.mean() - exact + var / 2) < 3.5 * bias_se, n
    assert runs[1000].var() / 2 < 0.2  # the bias -Var/2: under 0.2 nats at N = 1000, T = 100
    # Var ~ c / N: 4x the particles, a quarter of the variance (sampling error of each ~ 8 %)
    assert 2.8 < runs[250].var() / runs[1000].var() < 5.7


def test_bad_input_is_reported_before_any_work():
    pf, prior = particle_model(100)(THETA)
    with pytest.raises(ConfigError, match="rng"):
        log_likelihood(pf, prior, ZS)
    with pytest.raises(MeasurementError, match="t0"):
        LogLikelihood(ZS, t0=5.0)
    with pytest.raises(MeasurementError, match="measurements"):
        LogLikelihood([])
    with pytest.raises(ConfigError, match="rngs"):
        LogLikelihood(ZS).many([(pf, prior)] * 2, [np.random.default_rng(0)])


@pytest.mark.parametrize("step", [0, 40])
def test_a_degenerate_step_is_kept_as_the_filter_keeps_it(step):
    """An outlier no particle explains (evidence far below -708): the filter keeps the weights
    it had and adds the evidence estimate; the kernel does the same."""
    zs = list(ZS)
    zs[step] = Measurement(zs[step].time, "y", [1e3])
    pf, prior = particle_model(300)(THETA)
    fast = LogLikelihood(zs)(pf, prior, np.random.default_rng(2))
    with pytest.warns(DegenerateWeightsWarning):
        slow = _run_filter_ll(pf, prior, zs, np.random.default_rng(2))
    assert fast < -1e5
    assert fast == pytest.approx(slow, rel=1e-12)
