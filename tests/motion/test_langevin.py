"""Langevin centroid model (Zhai 2007, Sec. 3.5.2, with the decay sign corrected)."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.motion.langevin import Langevin


def test_decay_and_transition_match_the_spec_choice():
    m = Langevin()
    a = np.exp(-10.0 / 30.0)
    assert m.decay(1.0) == pytest.approx(0.7165, abs=1e-4)
    np.testing.assert_allclose(m.mean(np.array([1.0, 2.0, 3.0, -4.0]), 1.0), [4, -2, 3 * a, -4 * a])


def test_velocity_noise_keeps_the_stationary_speed():
    # a^2 P + b^2 = P  ->  P = b^2 / (1 - a^2) = v_mean^2
    m = Langevin(v_mean=5.0)
    a, q = m.decay(1.0), m.noise_cov(1.0)
    assert q[2, 2] / (1 - a * a) == pytest.approx(25.0)
    assert q[0, 0] == pytest.approx(0.25) and q[0, 2] == 0.0
    x = np.zeros((20000, 4))
    rng = np.random.default_rng(0)
    for _ in range(30):
        x = m.sample(x, 1.0, rng)
    assert x[:, 2].var() == pytest.approx(25.0, rel=0.05)


def test_app_b_limit_and_bad_parameters():
    m = Langevin(beta=0.0, v_mean=0.0, position_var=5.0)  # x += v + sqrt(5) N(0, 1), v fixed
    np.testing.assert_allclose(m.noise_cov(1.0), np.diag([5.0, 5.0, 0.0, 0.0]))
    np.testing.assert_allclose(m.mean(np.array([0.0, 0.0, 1.0, 2.0]), 1.0), [1, 2, 1, 2])
    with pytest.raises(ConfigError, match="beta"):
        Langevin(beta=-1.0)
