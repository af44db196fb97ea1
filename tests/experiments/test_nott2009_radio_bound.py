"""The best possible beside Table 5.1 (radio_bound): hand-computed CRLBs, the reading attaining
them in the linear-Gaussian cases, and the report's claims."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.experiments.nott2009 import radio
from fusetrack.experiments.nott2009.radio_bound import (
    bias_jacobian,
    known_field_crlb,
    reading_mmse,
)
from fusetrack.sensors import NferTagSimulator


def test_known_field_crlb_of_a_linear_field():
    # b(p) = 0.5 p: z = 1.5 p + w, so var(p) >= sigma^2 / 2.25 per axis
    B = known_field_crlb(lambda p: 0.5 * p, (0.1, 0.2), [[1.0, 2.0], [3.0, 4.0]])
    assert B == pytest.approx(np.broadcast_to(np.diag([0.01, 0.04]) / 2.25, (2, 2, 2)))
    # a shear: A = [[1, 1], [0, 1]], J = A^T A / s^2, CRLB = s^2 (A^T A)^-1
    B = known_field_crlb(lambda p: np.stack([p[..., 1], 0 * p[..., 0]], -1), (0.1, 0.1), [[0, 0]])
    A = np.array([[1.0, 1.0], [0.0, 1.0]])
    assert B[0] == pytest.approx(0.01 * np.linalg.inv(A.T @ A))
    with pytest.raises(ConfigError):
        known_field_crlb(lambda p: p, (0.0, 0.1), [[0, 0]])
    with pytest.raises(ConfigError):
        bias_jacobian(lambda p: p, [1.0, 2.0])


def test_bias_jacobian_of_the_simulated_field_matches_its_slope():
    tag = NferTagSimulator("field", sigma=(0.1, 0.1), field_seed=3)
    p = np.array([[6.5, 2.6]])
    J = bias_jacobian(tag.bias, p)[0]
    h = 1e-3
    for j in range(2):
        e = np.eye(2)[j] * h
        assert J[:, j] == pytest.approx((tag.bias(p + e) - tag.bias(p))[0] / h, abs=2e-3)


def test_white_tag_reading_attains_both_bounds():
    """No bias field: the reading is efficient, its error covariance the CRLB (and the MMSE)."""
    tag = NferTagSimulator("white", sigma=(0.3, 0.1))
    B = known_field_crlb(tag.bias, tag.sigma, [[1.0, 1.0]])[0]
    assert B == pytest.approx(reading_mmse(tag))
    e = tag.simulate(np.zeros((20000, 2)), np.random.default_rng(0))
    assert np.cov(e.T) == pytest.approx(B, abs=0.004)


def test_field_tag_attains_the_one_reading_mmse_over_buildings():
    rng = np.random.default_rng(1)
    err = [
        radio.tag_model(s).simulate(radio.TABLE_5_1_TRUTH, rng) - radio.TABLE_5_1_TRUTH
        for s in range(400)
    ]
    ms = np.mean(np.sum(np.square(err), axis=-1))
    bound = np.trace(reading_mmse(radio.tag_model(0)))
    assert ms / bound == pytest.approx(1.0, abs=0.08)


def test_best_claims_fail_for_a_wrong_bound_or_an_impossible_table():
    best = {"ours": (0.55, 0.005), "mmse_rms": 0.55, "mmse_mean": 0.46, "crlb_mean": 0.13}
    ok = radio._best_claims(best, 0.11)
    assert [c.holds for c in ok] == [True, True]
    too_low = radio._best_claims({**best, "mmse_rms": 0.45}, 0.11)
    too_high = radio._best_claims({**best, "mmse_rms": 0.65}, 0.11)
    assert not too_low[0].holds and not too_high[0].holds
    impossible = radio._best_claims({**best, "crlb_mean": 0.5}, 0.11)  # floor above 0.458
    assert not impossible[1].holds
    assert {c.kind for c in ok} == {"diagnostic"}
