"""The shared particle engine takes likelihood-only sensors: a value of any size goes to the
sensor's ``log_likelihood`` as given, and the weights are exactly ``log w + log p(z | x)``."""

import numpy as np
import pytest

from fusetrack.core import Measurement, Particles
from fusetrack.filters import BootstrapFilter
from fusetrack.motion import ConstantVelocity


class _Histogram:
    """A likelihood-only sensor: its report is a histogram over x of any length."""

    sensor_id = "hist"

    def log_likelihood(self, z, x):
        z = np.asarray(z, float)
        edges = np.linspace(0.0, 10.0, z.size + 1)
        cell = np.clip(np.searchsorted(edges, x[..., 0]) - 1, 0, z.size - 1)
        return np.log(z[cell] / z.sum())


@pytest.mark.parametrize("size", [3, 7])
def test_weights_are_prior_weights_times_the_sensors_likelihood(size):
    pf = BootstrapFilter(ConstantVelocity(ndim=1, q=0.1), [_Histogram()], n_particles=50)
    rng = np.random.default_rng(3)
    states = np.column_stack([rng.uniform(0, 10, 50), np.zeros(50)])
    prior = Particles(states, np.log(rng.uniform(0.5, 1.5, 50)))
    z = np.arange(1.0, size + 1.0)
    post, loglik = pf.update_with_likelihood(prior, [Measurement(0.0, "hist", z)])
    expected = prior.log_weights + _Histogram().log_likelihood(z, states)
    w = np.exp(expected - expected.max())
    np.testing.assert_allclose(pf.weights(post), w / w.sum(), rtol=1e-12)
    w0 = np.exp(prior.log_weights - prior.log_weights.max())
    ref = np.log(np.sum(w0 / w0.sum() * np.exp(_Histogram().log_likelihood(z, states))))
    assert float(loglik) == pytest.approx(ref, rel=1e-12)
