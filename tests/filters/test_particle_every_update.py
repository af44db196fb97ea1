"""ParticleFilter's second resampling policy, ``resample="every_update"`` (the SIS loop of
Zhai 2007 that ProposalParticleFilter and MultipleModelParticleFilter configure): hand-computed
weights, increment and estimates, the equivalences with the configurations, the guards."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusetrack.core import ConfigError, Gaussian, Measurement, Particles
from fusetrack.filters import (
    BootstrapFilter,
    MultipleModelParticleFilter,
    ParticleFilter,
    PriorProposal,
    ProposalParticleFilter,
    RegularizedParticleFilter,
    SISBelief,
)
from fusetrack.filters.mcmc_moves import RandomWalkMove
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix

FIX = PositionFix("p", cov=[[1.0]], position_index=(0,))
CV = ConstantVelocity(ndim=1, q=0.3)
PRIOR = Gaussian(np.array([0.0, 1.0]), np.diag([2.0, 0.5]))


def _three() -> SISBelief:
    """Particles at 0, 1, 2 (velocity 0), equally weighted, as a predicted SIS belief."""
    x = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    return SISBelief(x, np.full(3, -math.log(3)), estimate=x.mean(axis=0))


def test_update_weights_by_the_likelihood_and_reports_the_log_mean_likelihood():
    pf = ParticleFilter(CV, [FIX], n_particles=3, resample="every_update", estimate="resampled")
    lik = np.exp(-0.5 * (np.array([0.0, 1.0, 2.0]) - 2.0) ** 2) / math.sqrt(2 * math.pi)
    b, inc = pf.update_with_likelihood(_three(), [Measurement(1.0, "p", [2.0])], rng=_rng())
    assert inc == pytest.approx(math.log(lik.mean()), rel=1e-12)
    # systematic resampling of w = lik / sum(lik) with the generator's first uniform
    u = (np.arange(3) + np.random.default_rng(7).random()) / 3
    expect = np.searchsorted(np.cumsum(lik / lik.sum()), u, side="right")
    np.testing.assert_array_equal(b.states[:, 0], expect.astype(float))
    np.testing.assert_allclose(b.estimate, b.states.mean(axis=0), rtol=0, atol=0)
    np.testing.assert_array_equal(pf.mean(b), b.estimate)  # the cached estimate
    np.testing.assert_allclose(pf.weights(b), np.full(3, 1 / 3))  # equal after resampling
    assert pf.stats.resample_count == 1


def test_weighted_estimate_is_the_mean_before_resampling():
    pf = ParticleFilter(CV, [FIX], n_particles=3, resample="every_update", estimate="weighted")
    lik = np.exp(-0.5 * (np.array([0.0, 1.0, 2.0]) - 2.0) ** 2)
    b = pf.update(_three(), [Measurement(1.0, "p", [2.0])], rng=_rng())
    assert b.estimate[0] == pytest.approx(float(lik @ [0.0, 1.0, 2.0] / lik.sum()), rel=1e-12)


def test_the_sis_configurations_are_the_particle_filter():
    sis = ProposalParticleFilter(CV, [FIX], n_particles=300, move=RandomWalkMove(0.2))
    same = ParticleFilter(
        CV,
        [FIX],
        300,
        resample="every_update",
        estimate="resampled",
        proposal=PriorProposal(),
        move=RandomWalkMove(0.2),
    )
    mm = MultipleModelParticleFilter([CV, ConstantVelocity(ndim=1, q=2.0)], np.eye(2), [FIX], 50)
    assert isinstance(sis, ParticleFilter) and isinstance(mm, ParticleFilter)
    r1, r2 = np.random.default_rng(3), np.random.default_rng(3)
    a, b = sis.initialize(PRIOR, r1), same.initialize(PRIOR, r2)
    for k in range(5):
        ms = [Measurement(k + 1.0, "p", [1.1 * (k + 1)])]
        a, b = sis.step(a, 1.0, ms, r1), same.step(b, 1.0, ms, r2)
    np.testing.assert_array_equal(a.states, b.states)
    np.testing.assert_array_equal(a.estimate, b.estimate)


def test_step_of_the_ess_policy_is_predict_then_update():
    pf = BootstrapFilter(CV, [FIX], n_particles=200, ess_threshold=0.5)
    r1, r2 = np.random.default_rng(5), np.random.default_rng(5)
    a, b = pf.initialize(PRIOR, r1), pf.initialize(PRIOR, r2)
    for k in range(4):
        ms = [Measurement(k + 1.0, "p", [0.8 * k])] if k != 2 else []
        a = pf.step(a, 1.0, ms, r1)
        b = pf.predict(b, 1.0, r2)
        b = pf.update(b, ms, r2) if ms else b
    assert type(a) is Particles
    np.testing.assert_array_equal(a.states, b.states)
    np.testing.assert_array_equal(a.log_weights, b.log_weights)


def test_vanished_weights_keep_them_equal_and_never_nan():
    pf = ParticleFilter(CV, [FIX], n_particles=4, resample="every_update")
    b = pf.initialize(PRIOR, _rng())
    with pytest.warns(Warning, match="ParticleFilter"), np.errstate(over="ignore"):
        b2, inc = pf.update_with_likelihood(b, [Measurement(1.0, "p", [1e200])], _rng())
    assert inc == -np.inf and pf.stats.degenerate_steps == 1
    assert np.all(np.isfinite(b2.estimate))


@pytest.mark.parametrize(
    "kwargs",
    [
        {"proposal": PriorProposal()},
        {"move": RandomWalkMove(0.1)},
        {"estimate": "resampled"},
        {"transition": "marginal"},
        {"resample": "sometimes"},
        {"resample": "every_update", "estimate": "median"},
    ],
)
def test_sis_parts_need_the_every_update_policy(kwargs):
    with pytest.raises(ConfigError):
        ParticleFilter(CV, [FIX], 10, **kwargs)


def test_filters_with_their_own_selection_refuse_every_update():
    with pytest.raises(ConfigError, match="RegularizedParticleFilter"):
        RegularizedParticleFilter(CV, [FIX], 10, resample="every_update")


def test_proposals_draw_from_one_generator():
    pf = ProposalParticleFilter(CV, [FIX], n_particles=10)
    with pytest.raises(ConfigError, match="rng"):
        pf.initialize(PRIOR, [np.random.default_rng(0)], batch_shape=(1,))


def _rng() -> np.random.Generator:
    return np.random.default_rng(7)


def test_mean_of_a_sis_belief_is_its_estimate_even_when_replaced():
    import dataclasses

    pf = ProposalParticleFilter(CV, [FIX], n_particles=50)
    b = pf.step(pf.initialize(PRIOR, _rng()), 1.0, [Measurement(1.0, "p", [0.5])], _rng())
    np.testing.assert_array_equal(pf.mean(b), b.states.mean(axis=0))
    moved = dataclasses.replace(b, estimate=b.estimate + 1.0)  # e.g. App. B's shared velocity
    np.testing.assert_array_equal(pf.mean(moved), b.estimate + 1.0)
