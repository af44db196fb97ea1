"""gaussian_information and harmonic_frequency_crlb: hand-computed cases and Kay's sinusoid."""

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.evaluation import gaussian_information, harmonic_frequency_crlb


def test_gaussian_information_by_hand_with_and_without_an_offset():
    G = np.array([[1.0], [2.0], [3.0]])
    assert gaussian_information(G, 2.0)[0, 0] == pytest.approx(14.0 / 2.0)
    # an unknown offset removes the mean of G: [-1, 0, 1] -> 2 / 2
    assert gaussian_information(G, 2.0, np.ones((3, 1)))[0, 0] == pytest.approx(1.0)
    # a nuisance that explains G entirely leaves no information
    assert gaussian_information(G, 2.0, G)[0, 0] == pytest.approx(0.0, abs=1e-12)


def test_harmonic_frequency_crlb_by_hand():
    # one harmonic, A = 1, sigma = 1 (Kay's eta = 1/2), N = 3:
    # var = 12 / ((2 pi)^2 * 0.5 * 3 * 8) = 1 / (4 pi^2)
    one = harmonic_frequency_crlb([[1.0]], 1.0, 3)
    assert one == pytest.approx(1.0 / (2 * np.pi))
    # the second harmonic alone moves twice as fast: half the std; two channels: 1/sqrt(2)
    assert harmonic_frequency_crlb([[0.0, 1.0]], 1.0, 3) == pytest.approx(one / 2)
    assert harmonic_frequency_crlb([[1.0], [1.0]], 1.0, 3) == pytest.approx(one / np.sqrt(2))
    # in Hz: scales with fs
    assert harmonic_frequency_crlb([[1.0]], 1.0, 3, fs=100.0) == pytest.approx(100 * one)


def test_harmonic_frequency_crlb_matches_the_exact_fisher_information():
    """The exact CRLB of f0 with every amplitude and phase unknown (by gaussian_information on
    the model's derivatives) agrees with the asymptotic formula for a long record."""
    n, f0, amps, sigma = 2000, 0.0173, np.array([1.0, 0.5, 0.3]), 0.7
    t = np.arange(n)
    h = np.arange(1, 4)
    ph = np.array([0.3, 1.1, -0.4])
    arg = 2 * np.pi * h[None, :] * f0 * t[:, None] + ph  # (n, H)
    d_f0 = (-amps * np.sin(arg) * 2 * np.pi * h * t[:, None]).sum(1)[:, None]
    nuisance = np.hstack([np.cos(arg), -amps * np.sin(arg)])  # d/dA_h, d/dphi_h
    exact = 1 / np.sqrt(gaussian_information(d_f0, sigma**2, nuisance)[0, 0])
    assert exact == pytest.approx(float(harmonic_frequency_crlb(amps[None], sigma, n)), rel=0.01)


def test_bad_input_is_named():
    with pytest.raises(ConfigError, match="sigma"):
        harmonic_frequency_crlb([[1.0]], 0.0, 10)
    with pytest.raises(ConfigError, match="variance"):
        gaussian_information(np.ones((3, 1)), -1.0)
