"""SIS marginal transition weight: the Numba mixture pass equals the model's own log densities."""

import numpy as np
from scipy.special import logsumexp

from fusetrack.filters.sis import ProposalParticleFilter, is_gaussian_transition
from fusetrack.motion import ConstantVelocity
from fusetrack.motion.benchmark import ScalarBenchmark
from fusetrack.sensors import Bearing


def test_marginal_weight_fast_path_equals_direct_sum() -> None:
    motion = ConstantVelocity(q=0.05)
    f = ProposalParticleFilter(
        motion,
        [Bearing("s", position=[0.0, 0.0], sigma=0.1)],
        n_particles=40,
        transition="marginal",
    )
    rng = np.random.default_rng(0)
    x, prev = rng.normal(size=(3, 40, 4)), rng.normal(size=(3, 40, 4))
    direct = logsumexp(motion.log_density(x[..., :, None, :], prev[..., None, :, :], 1.0), axis=-1)
    np.testing.assert_allclose(f.log_transition(x, prev, 1.0), direct - np.log(40), rtol=1e-12)


def test_gaussian_transition_check() -> None:
    assert is_gaussian_transition(ConstantVelocity(q=0.05), 1.0)
    assert is_gaussian_transition(ScalarBenchmark(), 1.0)
    assert not is_gaussian_transition(ConstantVelocity(q=0.05, noise="discrete"), 1.0)  # rank 2
