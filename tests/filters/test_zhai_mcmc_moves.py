"""MCMC moves (Zhai 2007, Algorithms 8-10) leave their per-particle target invariant."""

import numpy as np
import pytest

from fusetrack.filters.mcmc_moves import IndependenceMove, MHPriorMove, RandomWalkMove
from fusetrack.filters.sis import ProposalParticleFilter, SISStats
from fusetrack.motion import RandomWalk
from fusetrack.sensors import PositionFix

# target per particle: p(z | x) p(x | parent) with x | parent ~ N(parent, 1), z | x ~ N(x, 0.5)
Q, R, Z = 1.0, 0.5, 1.2


def _posterior(parent):
    var = 1.0 / (1.0 / Q + 1.0 / R)
    return var * (parent / Q + Z / R), var


class _Filt:
    motion = RandomWalk(dim=1, q=Q)
    stats = SISStats()


def _loglik(x):
    return -0.5 * (Z - x[..., 0]) ** 2 / R


@pytest.mark.parametrize(
    "move",
    [
        MHPriorMove(n_iter=3),
        RandomWalkMove(variance=0.2, n_iter=3),
        IndependenceMove(variance=1.5, n_iter=3),
    ],
)
def test_move_leaves_the_target_invariant(move):
    """Start from exact target draws; after 3 iterations the mean and variance are unchanged.

    A kernel with a wrong acceptance ratio (e.g. the RWM without the prior term, or the MIS
    without dividing by T) shifts the mean by > 0.1 or the variance by > 15 %, far beyond these
    tolerances (n = 200 000: s.e. of the mean ~0.0013, of the variance ~0.3 %).
    """
    rng = np.random.default_rng(7)
    n = 200_000
    parents = rng.normal(0.0, 1.0, (n, 1))
    mean, var = _posterior(parents)
    x = mean + np.sqrt(var) * rng.standard_normal((n, 1))
    out = move(x, parents, _loglik, 1.0, rng, _Filt())
    resid = (out - mean) / np.sqrt(var)
    assert abs(resid.mean()) < 0.01
    assert abs(resid.var() - 1.0) < 0.02
    assert np.mean(out != x) > 0.05  # it did move


def test_zero_acceptance_is_counted():
    filt = _Filt()
    filt.stats = SISStats()
    rng = np.random.default_rng(0)
    x = np.full((50, 1), Z)
    far = IndependenceMove(variance=1e-4, mean=40.0)  # proposals far out in the tail
    out = far(x, np.full((50, 1), Z), _loglik, 1.0, rng, filt)
    np.testing.assert_array_equal(out, x)
    assert filt.stats.zero_acceptance_steps == 1 and filt.stats.moves_accepted == 0


def test_move_inside_the_filter_keeps_the_kalman_mean():
    """Random walk + position fix: the resample-move filter's mean is the Kalman mean."""
    motion = RandomWalk(dim=1, q=Q)
    sensor = PositionFix("p", cov=[[R]], position_index=(0,))
    pf = ProposalParticleFilter(motion, [sensor], n_particles=400, move=RandomWalkMove(0.3))
    from fusetrack.core import Gaussian, Measurement

    rng = np.random.default_rng(2)
    state = pf.initialize(Gaussian(np.zeros(1), np.eye(1)), rng, batch_shape=(300,))
    state = pf.step(state, 1.0, [Measurement(1.0, "p", [Z])], rng)
    kalman_mean = 2.0 / (2.0 + R) * Z  # prior N(0, 1 + Q)
    assert abs(state.estimate.mean() - kalman_mean) < 4 * state.estimate.std() / np.sqrt(300) + 2e-3
    assert 0.2 < pf.stats.acceptance_rate < 0.95
