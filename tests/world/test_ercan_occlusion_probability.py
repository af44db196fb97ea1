"""Occlusion probabilities of Ercan et al. 2013: Eq. 7 (and its frame-free form), Eqs. 8-9."""

import itertools

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.world.occlusion import (
    OccluderPriors,
    all_visible_probability,
    disks_block,
    disks_block_reference,
    occlusion_probability,
    occlusion_probability_eq7,
    occlusion_probability_mc,
    occlusion_probability_reference,
    pattern_probability,
    pattern_probability_reference,
)

D = 3.33


def random_prior(rng, alpha):
    rot = rng.uniform(0, np.pi)
    R = np.array([[np.cos(rot), -np.sin(rot)], [np.sin(rot), np.cos(rot)]])
    return R @ np.diag([4.0, 4.0 / alpha]) @ R.T


def test_frame_free_form_equals_eq7_as_printed():
    rng = np.random.default_rng(1)
    for _ in range(50):
        c, x = rng.uniform(0, 100, 2), rng.uniform(0, 100, 2)
        mu = c + rng.uniform(-0.2, 1.2) * (x - c) + rng.normal(0, 3, 2)
        cov = random_prior(rng, rng.uniform(1, 8))
        pri = OccluderPriors(mu[None], cov[None])
        ref = occlusion_probability_reference(c[None], x[None], pri, D)[0, 0, 0]
        fast = occlusion_probability(c[None], x[None], pri, D)[0, 0, 0]
        printed = occlusion_probability_eq7(c, x, mu, cov, D)
        assert ref == pytest.approx(printed, abs=1e-12)
        assert fast == pytest.approx(printed, abs=1e-6)


def test_eq7_against_monte_carlo_isotropic_is_exact():
    """alpha = 1: Eq. 7 is the exact rectangle probability, so MC agrees within 4 standard errors."""
    rng = np.random.default_rng(2)
    n = 40_000
    for _ in range(12):
        c, x = np.zeros(2), rng.uniform(10, 50, 2)
        mu = rng.uniform(0.1, 0.9) * x + rng.normal(0, 2, 2)
        cov = 4.0 * np.eye(2)
        q = occlusion_probability_eq7(c, x, mu, cov, D)
        mc = occlusion_probability_mc(c, x, mu, cov, D, n, rng)
        se = np.sqrt(max(q * (1 - q), 1e-4) / n)
        assert abs(q - mc) < 4 * se


def test_eq7_is_an_approximation_when_anisotropic_but_close():
    rng = np.random.default_rng(3)
    errs = []
    for _ in range(20):
        x = rng.uniform(10, 50, 2)
        mu = 0.5 * x + rng.normal(0, 2, 2)
        cov = random_prior(rng, 4.0)
        errs.append(
            abs(
                occlusion_probability_eq7(np.zeros(2), x, mu, cov, D)
                - occlusion_probability_mc(np.zeros(2), x, mu, cov, D, 20_000, rng)
            )
        )
    assert (
        np.mean(errs) < 0.03
    )  # App. C: "most points within tolerance"; a wrong formula is off by ~0.1+


def test_kernels_match_references():
    rng = np.random.default_rng(4)
    m = 25
    pri = OccluderPriors(
        rng.uniform(0, 100, (m, 2)),
        np.array([random_prior(rng, rng.uniform(1, 5)) * rng.uniform(1, 10) for _ in range(m)]),
    )
    cams = rng.uniform(0, 100, (4, 2))
    x = rng.uniform(0, 100, (300, 2))
    q = occlusion_probability(cams, x, pri, D)
    assert np.abs(q - occlusion_probability_reference(cams, x, pri, D)).max() < 1e-6
    A = rng.random((4, 300)) < 0.8
    for eta in itertools.product([False, True], repeat=4):
        e = np.array(eta)
        for clamp in (True, False):
            assert np.allclose(
                pattern_probability(q, e, A, clamp),
                pattern_probability_reference(q, e, A, clamp),
                atol=1e-12,
            )
    assert (
        disks_block(cams, x, pri.mean, 6.0) == disks_block_reference(cams, x, pri.mean, 6.0)
    ).all()


def test_pattern_probabilities_sum_to_one_and_clamp_into_unit_interval():
    rng = np.random.default_rng(5)
    for k in (1, 2, 3, 5):
        pri = OccluderPriors(
            rng.uniform(0, 100, (30, 2)), np.broadcast_to(20 * np.eye(2), (30, 2, 2))
        )
        q = occlusion_probability(rng.uniform(0, 100, (k, 2)), rng.uniform(0, 100, (64, 2)), pri, D)
        A = rng.random((k, 64)) < 0.7
        raw = [
            pattern_probability(q, np.array(e), A, clamp=False)
            for e in itertools.product([False, True], repeat=k)
        ]
        assert np.allclose(np.sum(raw, axis=0), 1.0, atol=1e-12)
        clamped = [
            pattern_probability(q, np.array(e), A)
            for e in itertools.product([False, True], repeat=k)
        ]
        assert np.all((np.array(clamped) >= 0) & (np.array(clamped) <= 1))


def test_recursion_example_of_the_paper():
    """N = 3, eta = (1, 0, 0): p = p_1 - p_12 - p_13 + p_123 (Sec. 4.2)."""
    rng = np.random.default_rng(6)
    pri = OccluderPriors(rng.uniform(0, 100, (10, 2)), np.broadcast_to(30 * np.eye(2), (10, 2, 2)))
    q = occlusion_probability(rng.uniform(0, 100, (3, 2)), rng.uniform(0, 100, (20, 2)), pri, D)

    def pQ(*cams):
        sel = np.zeros(3, bool)
        sel[list(cams)] = True
        return all_visible_probability(q, sel)

    expected = pQ(0) - pQ(0, 1) - pQ(0, 2) + pQ(0, 1, 2)
    got = pattern_probability(q, np.array([True, False, False]), clamp=False)
    assert np.allclose(got, expected)


def test_single_camera_and_no_occluders():
    rng = np.random.default_rng(7)
    pri = OccluderPriors(rng.uniform(0, 100, (8, 2)), np.broadcast_to(9 * np.eye(2), (8, 2, 2)))
    q = occlusion_probability(rng.uniform(0, 100, (1, 2)), rng.uniform(0, 100, (50, 2)), pri, D)
    assert np.allclose(pattern_probability(q, np.array([True])), np.prod(1 - q[0], axis=-1))
    # no moving occluders: deterministic visibility from the partition alone
    q0 = np.zeros((2, 50, 0))
    A = rng.random((2, 50)) < 0.5
    p = pattern_probability(q0, np.array([True, False]), A)
    assert np.array_equal(p, (A[0] & ~A[1]).astype(float))


def test_singular_and_invalid_prior_covariances():
    pri = OccluderPriors(np.array([[5.0, 0.2]]), np.zeros((1, 2, 2)))  # a point prior: regularised
    q = occlusion_probability(np.zeros((1, 2)), np.array([[10.0, 0.0], [10.0, 5.0]]), pri, D)
    assert np.all(np.isfinite(q))
    assert q[0, 0, 0] == pytest.approx(1.0) and q[0, 1, 0] == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(ConfigError, match="positive semi-definite"):
        OccluderPriors(np.zeros((1, 2)), np.array([[[1.0, 0.0], [0.0, -2.0]]]))
    with pytest.raises(ConfigError, match="symmetric"):
        OccluderPriors(np.zeros((1, 2)), np.array([[[1.0, 0.5], [0.0, 1.0]]]))
