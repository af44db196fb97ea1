"""The shared scalar-Gaussian part of Power and AcousticIntensity, by hand-computed values."""

import math

import numpy as np
import pytest

from fusetrack.sensors.acoustic_intensity import AcousticIntensity
from fusetrack.sensors.power import Power


def test_power_likelihood_and_information_by_hand() -> None:
    s = Power("p", exponent=2, sigma=2.0)
    x = np.array([3.0, 0.0])
    # h = 9, H = [2 * 3, 0]; r = (10 - 9) / 2
    assert s.log_likelihood(np.array([10.0]), x) == pytest.approx(
        -0.5 * 0.25 - math.log(2.0) - 0.5 * math.log(2 * math.pi)
    )
    np.testing.assert_allclose(s.fisher_information(x), [[9.0, 0.0], [0.0, 0.0]])
    np.testing.assert_array_equal(s.noise_cov(), [[4.0]])
    assert (s.dim, s.angular) == (1, (False,))


def test_intensity_likelihood_and_information_by_hand() -> None:
    s = AcousticIntensity("mic", position=[0.0, 0.0], source_db=70.0, alpha=2.0, sigma_db=0.5)
    x = np.array([10.0, 0.0, 0.0, 0.0])
    # h = 70 - 10 log10(10) = 60; dh/dx = -10 / (ln 10 * 10)
    g = -10.0 / (math.log(10.0) * 10.0)
    assert s.log_likelihood(np.array([61.0]), x) == pytest.approx(
        -0.5 * 4.0 - math.log(0.5) - 0.5 * math.log(2 * math.pi)
    )
    assert s.fisher_information(x)[0, 0] == pytest.approx(g * g / 0.25)
    np.testing.assert_array_equal(s.detection_probability(np.zeros((3, 4))), np.ones(3))


def test_simulate_draws_one_normal_per_measurement() -> None:
    s = Power("p", exponent=1, sigma=3.0)
    x = np.zeros((4, 1))
    z = s.simulate(x, np.random.default_rng(5))
    np.testing.assert_array_equal(z, 3.0 * np.random.default_rng(5).standard_normal((4, 1)))
