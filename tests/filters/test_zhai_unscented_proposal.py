"""Unscented-proposal PF (beyond the paper) keeps the Kalman mean on a linear-Gaussian model."""

import numpy as np

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import KalmanFilter, run_filter
from fusetrack.filters.sis import ProposalParticleFilter
from fusetrack.filters.unscented_proposal import UnscentedProposal
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix


def test_upf_mean_is_the_kalman_mean():
    motion = ConstantVelocity(ndim=1, q=0.5)
    sensor = PositionFix("p", cov=[[0.8]], position_index=(0,))
    prior = Gaussian(np.array([1.0, -0.5]), np.diag([2.0, 0.7]))
    zs = [[np.array([z])] for z in (0.9, 1.4, 0.3, -0.2)]
    kf, b = KalmanFilter(motion, [sensor]), prior
    for k, (z,) in enumerate(zs):
        b = kf.update(kf.predict(b, 1.0), [Measurement(float(k), "p", z)])
    pf = ProposalParticleFilter(motion, [sensor], UnscentedProposal(), n_particles=300)
    rng = np.random.default_rng(0)
    ms = [Measurement(k + 1.0, "p", z) for k, (z,) in enumerate(zs)]
    final = run_filter(pf, pf.initialize(prior, rng, (200,)), ms, rng=rng, t0=0.0).means[-1]
    se = final.std(axis=0) / np.sqrt(len(final))
    assert np.all(np.abs(final.mean(axis=0) - b.mean) < 4 * se + 1e-3)
