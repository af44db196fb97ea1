"""Multiple-model particle filters (Zhai 2007, Algorithms 3-4)."""

from dataclasses import dataclass

import numpy as np
import pytest

from fusetrack.core import ConfigError, Gaussian, Measurement, Particles
from fusetrack.filters.multiple_model import (
    MultipleModelParticleFilter,
    check_transition,
    hmm_filter,
    sample_regimes,
    stationary_distribution,
)
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix

PI_A = [[0.7, 0.1, 0.1, 0.1], [0.4, 0.5, 0.05, 0.05], [0.4, 0.3, 0.2, 0.1], [0.4, 0.3, 0.2, 0.1]]


@dataclass(frozen=True)
class Jump:
    """x' = level + N(0, q): the state forgets its past, so the regime is all that matters."""

    level: float
    q: float = 0.01
    dim: int = 1
    position_index: tuple = (0,)

    def mean(self, x, dt):
        return np.full(np.shape(x), self.level)

    def jacobian(self, x, dt):
        return np.zeros((*np.shape(x)[:-1], 1, 1))

    def noise_cov(self, dt):
        return np.array([[self.q]])

    def sample(self, x, dt, rng):
        return self.level + np.sqrt(self.q) * rng.standard_normal(np.shape(x))

    def log_density(self, xn, x, dt):
        return -0.5 * ((xn[..., 0] - self.level) ** 2 / self.q + np.log(2 * np.pi * self.q))


def test_stationary_distribution_of_pi_a():
    """Spec Sec. 2.7: Pi_A -> [0.5714, 0.2321, 0.1080, 0.0884] (claim C9's ordering)."""
    np.testing.assert_allclose(
        stationary_distribution(PI_A), [0.5714, 0.2321, 0.1080, 0.0884], atol=1e-4
    )


def test_regime_sampling_follows_the_rows():
    rng = np.random.default_rng(0)
    modes = np.full(200_000, 1)
    nxt = sample_regimes(modes, np.array(PI_A), rng)
    np.testing.assert_allclose(np.bincount(nxt, minlength=4) / modes.size, PI_A[1], atol=0.005)


def _model_probs(mm, zs, rng, batch_shape=()):
    """Regime shares ``(T, *batch, M)`` after each step of ``zs`` (sensor "p", dt 1)."""
    b = mm.initialize(Gaussian(np.zeros(1), np.eye(1)), rng, batch_shape)
    out = []
    for k, z in enumerate(zs):
        b = mm.step(b, 1.0, [Measurement(k + 1.0, "p", [z])], rng)
        out.append(b.proposal.model_probs)
    return np.array(out)


@pytest.mark.parametrize("proposal", ["prior", "sp-pekf"])
def test_model_probabilities_match_the_exact_hmm_filter(proposal):
    """With a discrete state the MM-PF's regime shares are the HMM filter's posterior."""
    levels = (-1.0, 0.0, 1.5)
    models = [Jump(c) for c in levels]
    pi = np.array([[0.8, 0.1, 0.1], [0.2, 0.7, 0.1], [0.2, 0.1, 0.7]])
    r = 0.3
    sensor = PositionFix("p", cov=[[r]], position_index=(0,))
    zs = [0.1, -0.9, 1.2, 0.7, 1.6, -0.2]
    ll = np.array([[-0.5 * (z - c) ** 2 / (r + 0.01) for c in levels] for z in zs])
    exact = hmm_filter(pi, ll, np.full(3, 1 / 3) @ np.linalg.matrix_power(pi, 0))
    mm = MultipleModelParticleFilter(models, pi, [sensor], 4000, proposal=proposal, n_channels=4)
    probs = _model_probs(mm, zs, np.random.default_rng(1), batch_shape=(20,))
    np.testing.assert_allclose(probs.mean(axis=1), exact, atol=0.02)


def test_discretisation_mmpf_matches_the_exact_hmm_filter():
    """Algorithm 7 (regime cells, marginal weights) gives the same regime posterior."""
    levels = (-1.0, 0.0, 1.5)
    pi = np.array([[0.8, 0.1, 0.1], [0.2, 0.7, 0.1], [0.2, 0.1, 0.7]])
    sensor = PositionFix("p", cov=[[0.3]], position_index=(0,))
    zs = [0.1, -0.9, 1.2, 0.7]
    ll = np.array([[-0.5 * (z - c) ** 2 / 0.31 for c in levels] for z in zs])
    exact = hmm_filter(pi, ll, np.full(3, 1 / 3))
    probs = []
    for r in range(8):
        mm = MultipleModelParticleFilter(
            [Jump(c) for c in levels], pi, [sensor], 600, proposal="cells"
        )
        probs.append(_model_probs(mm, zs, np.random.default_rng(r)))
    np.testing.assert_allclose(np.mean(probs, axis=0), exact, atol=0.04)


def test_bad_transition_matrices_are_refused():
    with pytest.raises(ValueError, match="transition"):
        check_transition([[0.5, 0.4], [0.5, 0.5]], 2)
    with pytest.raises(ValueError, match=r"transition\.shape"):
        check_transition(np.eye(3), 2)
    with pytest.raises(ValueError, match="models"):
        MultipleModelParticleFilter(
            [ConstantVelocity(), ConstantVelocity(ndim=3)], np.eye(2) * 0 + 0.5, []
        )


def test_cells_and_propose_expose_one_discretisation_step():
    """Algorithm 7's accessors (Figs 55-56): one cell set per model, centred on that model's
    level, and every proposed particle inside a box of its own regime's cells; the regime shares
    follow the transition rows from uniform initial regimes (Eq. 47)."""
    levels = (-1.0, 0.0, 1.5)
    pi = np.array([[0.8, 0.1, 0.1], [0.2, 0.7, 0.1], [0.2, 0.1, 0.7]])
    sensor = PositionFix("p", cov=[[0.3]], position_index=(0,))
    mm = MultipleModelParticleFilter(
        [Jump(c) for c in levels], pi, [sensor], 3000, proposal="cells"
    )
    rng = np.random.default_rng(3)
    b = mm.initialize(Gaussian(np.zeros(1), np.eye(1)), rng)
    ms = [Measurement(1.0, "p", [0.2])]
    cells = mm.cells(b, 1.0, ms)
    assert len(cells) == 3
    for (centres, w, _), level in zip(cells, levels):
        np.testing.assert_allclose(centres[:, 0], level)  # Jump forgets the past: one point
        assert np.isclose(w.sum(), 1.0)
    x, modes = mm.propose(b, 1.0, ms, rng)
    assert x.shape == (3000, 1) and modes.shape == (3000,)
    for r, (centres, _, delta) in enumerate(cells):
        d = np.abs(x[modes == r, None, 0] - centres[None, :, 0])
        assert np.all(np.any(d <= delta[0] / 2 + 1e-12, axis=1))
    np.testing.assert_allclose(np.bincount(modes) / 3000, pi.mean(axis=0), atol=0.03)


def test_cells_and_propose_refuse_what_they_cannot_use():
    sensor = PositionFix("p", cov=[[0.3]], position_index=(0,))
    pi = [[0.9, 0.1], [0.1, 0.9]]
    mm = MultipleModelParticleFilter([Jump(0.0), Jump(1.0)], pi, [sensor], 50, proposal="cells")
    rng = np.random.default_rng(0)
    ms = [Measurement(1.0, "p", [0.2])]
    batch = mm.initialize(Gaussian(np.zeros(1), np.eye(1)), rng, (2,))
    with pytest.raises(ConfigError, match="batch_shape"):
        mm.cells(batch, 1.0, ms)
    with pytest.raises(ConfigError, match=r"belief\.proposal"):
        mm.propose(Particles(np.zeros((50, 1)), np.zeros(50)), 1.0, ms, rng)
