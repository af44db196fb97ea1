"""Occlusion probabilities of Ercan et al. 2013: Eq. 7 (and its frame-free form), Eqs. 8-9."""

import itertools

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError, ShapeError
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
from fusetrack.world.occlusion_kernels import occlusion_probability_kernel

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


def test_prior_draw_hits_rectangle_and_disc_events():
    """The Monte Carlo events of App. C by hand (camera at the origin, object at (10, 0), D = 3.33):
    a centre on the sight line is in both; 3 units beside it (> D/2) in neither; 1 unit past the
    object in the disc event only (the rectangle ends at the object); 1.5 units behind the camera
    in the disc event only too."""
    from fusetrack.world import prior_draw_hits_kernel

    centres = np.array([[5.0, 0.0], [5.0, 3.0], [11.0, 0.0], [-1.5, 0.0]])
    x = np.tile([10.0, 0.0], (4, 1))
    chol = np.tile(np.eye(2), (4, 1, 1))
    z = np.zeros((4, 1, 2))
    rect, disk = prior_draw_hits_kernel(x, centres, chol, z, D)
    np.testing.assert_array_equal(rect, [1.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(disk, [1.0, 0.0, 1.0, 1.0])


def test_prior_draw_hits_match_numpy_draws():
    """Shares of the draws ``mu + chol z`` equal a NumPy count of the same events."""
    from fusetrack.world import prior_draw_hits_kernel

    rng = np.random.default_rng(4)
    n_pts, n = 6, 2000
    x = rng.uniform(5, 30, (n_pts, 2))
    mu = x * rng.uniform(0.2, 0.9, (n_pts, 1)) + rng.normal(0, 2, (n_pts, 2))
    chol = np.linalg.cholesky(np.stack([random_prior(rng, 4.0) for _ in range(n_pts)]))
    z = rng.standard_normal((n_pts, n, 2))
    draws = mu[:, None, :] + np.einsum("pij,pnj->pni", chol, z)
    r = np.hypot(x[:, 0], x[:, 1])
    u = x / r[:, None]
    along = np.einsum("pni,pi->pn", draws, u)
    across = draws[..., 1] * u[:, None, 0] - draws[..., 0] * u[:, None, 1]
    rect = np.mean((along >= 0) & (along <= r[:, None]) & (np.abs(across) <= D / 2), axis=1)
    t = np.clip(np.einsum("pni,pi->pn", draws, x) / (r * r)[:, None], 0, 1)
    dist = np.linalg.norm(draws - t[..., None] * x[:, None, :], axis=-1)
    disk = np.mean(dist < D / 2, axis=1)
    got_rect, got_disk = prior_draw_hits_kernel(x, mu, chol, z, D)
    np.testing.assert_allclose(got_rect, rect, atol=1.5 / n)  # a draw on an edge may round apart
    np.testing.assert_allclose(got_disk, disk, atol=1.5 / n)
    assert 0 < rect.mean() < 1 and np.all(disk >= rect - 1.5 / n)


def test_tabulated_normal_cdf_error_is_the_documented_bound():
    """The table lookup errs by < 3.3e-8 (h^2 phi(1) / 8 for the grid step h), reached near |t| = 1,
    and is exact (0 or 1) beyond the table's +-8.5."""
    import math

    from scipy.special import ndtr

    from fusetrack.world.occlusion_kernels import _TABLE_STEP, _phi_fast

    t = np.linspace(-9.0, 9.0, 180_001)
    err = np.abs(np.array([_phi_fast(float(v)) for v in t]) - ndtr(t))
    bound = _TABLE_STEP**2 / 8 * math.exp(-0.5) / math.sqrt(2 * math.pi)
    assert err.max() < 3.3e-8
    assert err.max() > 0.9 * bound  # the bound is what the table really reaches
    assert abs(abs(t[err.argmax()]) - 1.0) < 0.05
    assert _phi_fast(-8.5) == 0.0 and _phi_fast(8.5) == 1.0


def test_row_of_occluders_is_the_one_triple_formula_bit_for_bit():
    """``_q_row_iso`` (four passes, so that it vectorises) gives exactly ``_q_iso``'s q for every
    occluder: near, far (skipped), behind the camera, beyond the point, and with CDF arguments in
    the exact tails beyond +-8.5."""
    import numba

    from fusetrack.world.occlusion_kernels import _ROW_WORK, _q_iso, _q_row_iso

    @numba.njit
    def both(u, m, inv_sd, reach, half, out_row, out_one):
        n = m.shape[0]
        work, index = np.empty((_ROW_WORK, n + 3)), np.empty((4, n + 3), dtype=np.int32)
        for l in range(u.shape[0]):
            _q_row_iso(u[l, 0], u[l, 1], u[l, 2], m[:, 0].copy(), m[:, 1].copy(), inv_sd, reach,
                       half, n, out_row[l], work, index)  # fmt: skip
            for j in range(n):
                out_one[l, j] = _q_iso(
                    u[l, 0], u[l, 1], u[l, 2], m[j, 0], m[j, 1], inv_sd[j], reach[j], half
                )

    rng = np.random.default_rng(3)
    n, lines = 37, 400
    m = rng.uniform(-40, 40, (n, 2))
    sd = rng.choice([0.05, 0.5, 2.0, 8.0, 32.0], n)
    ang = rng.uniform(0, 2 * np.pi, lines)
    u = np.c_[np.cos(ang), np.sin(ang), rng.uniform(-1.0, 45.0, lines)]
    out_row, out_one = np.zeros((lines, n)), np.zeros((lines, n))
    both(u, m, 1 / sd, 5 * sd, D / 2, out_row, out_one)
    assert np.array_equal(out_row, out_one)
    assert 0.05 < np.mean(out_one == 0.0) < 0.95 and out_one.max() > 0.5  # both kinds occur


@pytest.mark.parametrize("cov", [np.eye(2) * 4.0, np.array([[4.0, 1.0], [1.0, 2.0]])])
def test_non_finite_points_give_nan_not_a_read_outside_the_table(cov):
    """In the kernel, a NaN or infinite point (isotropic priors: the vectorised row; correlated
    ones: the one-triple formula) gives NaN q instead of a table index outside the table; the
    finite point's q is unchanged. The public function refuses such points before the kernel,
    naming the first one."""
    pri = OccluderPriors(np.array([[1.0, 2.0], [3.0, 1.0]]), np.broadcast_to(cov, (2, 2, 2)))
    finite = occlusion_probability(np.zeros((1, 2)), np.array([[2.0, 2.0]]), pri, D)
    x = np.array([[2.0, 2.0], [np.nan, 1.0], [np.inf, 0.0], [1.0, -np.inf]])
    q = occlusion_probability_kernel(np.zeros((1, 2)), x, pri.mean, pri.cov, D)
    np.testing.assert_array_equal(q[:, 0], finite[:, 0])
    assert np.all(finite > 0) and np.all(np.isnan(q[:, 1:]))
    with pytest.raises(ConfigError, match=r"points\[1\]=\[nan, 1.0\] is invalid"):
        occlusion_probability(np.zeros((1, 2)), x, pri, D)
    with pytest.raises(ConfigError, match=r"viewers\[0\]=\[inf, 0.0\] is invalid"):
        occlusion_probability([[np.inf, 0.0]], x[:1], pri, D)
    with pytest.raises(ShapeError, match="2 numbers per point"):
        occlusion_probability(np.zeros((1, 2)), [1.0, 2.0, 3.0], pri, D)


def test_isotropic_priors_equal_the_general_constructor():
    """OccluderPriors.isotropic is the constructor with cov = var I, bit for bit, and refuses or
    regularises what the constructor does."""
    rng = np.random.default_rng(8)
    mu = rng.uniform(0, 100, (12, 2))
    for var in (7.3, 1e-12, 0.0):  # the last two: floored to MIN_PRIOR_VARIANCE by the constructor
        fast, general = OccluderPriors.isotropic(mu, var), OccluderPriors(mu, var * np.eye(2))
        assert np.array_equal(fast.mean, general.mean) and np.array_equal(fast.cov, general.cov)
    assert len(OccluderPriors.isotropic(np.zeros((0, 2)), 4.0)) == 0
    bad = mu.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ConfigError, match=r"occluder priors' means\[3\]"):
        OccluderPriors.isotropic(bad, 4.0)
    with pytest.raises(ConfigError):
        OccluderPriors.isotropic(mu, np.inf)
    with pytest.raises(ConfigError):
        OccluderPriors.isotropic(mu, -1.0)  # not positive semi-definite


def test_exact_cull_skips_only_occluders_far_from_every_sight_line():
    """With isotropic priors the selection kernels compute q only for the occluders that
    ``_cull_occluders(exact=True)`` keeps; every one it drops is far (q exactly 0) for every
    sight line of the cloud, so the kernel's q is the one-triple formula bit for bit. Clouds of
    several spreads, occluder sds from narrow to wide, exclusion on, off and negative (the
    kernel's rectangles then reach past the point); the cull must drop a good share, or the test
    would not test it."""
    import numba

    from fusetrack.world.occlusion_kernels import (
        CUTOFF,
        _cull_occluders,
        _q_iso,
        _sight_line,
    )

    @numba.njit
    def one_triple_q(cams, x, mu, sd, half, exclusion):
        K, L, M = cams.shape[0], x.shape[0], mu.shape[0]
        out = np.zeros((K, L, M))
        for i in range(K):
            for l in range(L):
                u1, u2, r_eff = _sight_line(x[l, 0] - cams[i, 0], x[l, 1] - cams[i, 1], exclusion)
                if r_eff <= 0.0:
                    continue
                for j in range(M):
                    m1, m2 = mu[j, 0] - cams[i, 0], mu[j, 1] - cams[i, 1]
                    out[i, l, j] = _q_iso(u1, u2, r_eff, m1, m2, 1 / sd[j], CUTOFF * sd[j], half)
        return out

    rng = np.random.default_rng(11)
    dropped = kept = 0
    for spread, exclusion in [(2.0, 0.0), (10.0, 3.33), (20.0, 0.0), (10.0, -30.0)]:
        m = 29  # not a whole number of SIMD blocks
        mu = rng.uniform(0, 200, (m, 2))
        sd = rng.choice([0.3, 2.0, 6.0, 15.0], m)
        cov = sd[:, None, None] ** 2 * np.eye(2)
        cams = np.array([[0.0, 0.0], [200.0, 0.0], [0.0, 200.0], [100.0, 200.0], [200.0, 90.0]])
        x = rng.uniform(60, 140, 2) + rng.normal(0, spread, (400, 2))
        q = occlusion_probability_kernel(cams, x, mu, cov, D, exclusion)
        np.testing.assert_array_equal(q, one_triple_q(cams, x, mu, sd, D / 2, exclusion))
        _, n_use = _cull_occluders(x, cams, mu, cov, D / 2, True, exclusion)
        assert 0 < (m - n_use).sum() < m * len(cams)  # some dropped, some kept
        dropped += int((m - n_use).sum())
        kept += int(n_use.sum())
    assert 0.2 * (dropped + kept) < dropped < 0.8 * (dropped + kept)


def test_row_length_rounds_up_to_whole_blocks_unless_one_or_two_are_left():
    from fusetrack.world.occlusion_kernels import _LANES, _row_length

    assert _LANES == 8
    got = [_row_length(n) for n in range(0, 20)]
    assert got == [0, 1, 2, 8, 8, 8, 8, 8, 8, 9, 10, 16, 16, 16, 16, 16, 16, 17, 18, 24]


def test_padded_rows_stay_inside_their_arrays():
    """Rows of Eq. 7 run padded to whole SIMD blocks (``_row_length``): the likelihood and selection
    kernels, run with Numba's bounds checks on (a fresh process, its own cache), give the same
    numbers as here for 13 occluders, 2 cameras and 50 particles, and read or write nothing
    outside an array."""
    import json
    import os
    import subprocess
    import sys
    import tempfile
    import textwrap

    code = textwrap.dedent(
        """
        import json
        import numpy as np
        from fusetrack.world import occlusion_kernels as k
        rng = np.random.default_rng(5)
        mu = rng.uniform(0, 20, (13, 2))
        cov = np.broadcast_to(np.eye(2) * 4.0, (13, 2, 2)).copy()
        cams = np.array([[0.0, 0.0], [20.0, 0.0]])
        x = rng.uniform(2, 18, (50, 2))
        z = np.array([np.nan, 3.0])
        lik = k.camera_likelihood_kernel(
            x, z, cams, np.array([0.8, 2.3]), np.ones(2), np.full(2, 100.0), np.full(2, 1e-4),
            np.full(2, 1e-2), np.ones(2), np.zeros((0, 2)), np.zeros((0, 2)),
            np.zeros(50, dtype=np.bool_), 2, mu, cov, 1.0, 0.0, 1e-12)
        q = k.occlusion_probability_kernel(cams, x, mu, cov, 1.0)
        p1, p2 = k.pair_visibility_of_priors_kernel(
            cams, x, mu, cov, 1.0, 0.0, np.ones((2, 50), dtype=np.bool_), np.full(50, 0.02))
        print(json.dumps([lik.tolist(), q.sum(), p1.tolist(), p2.tolist()]))
        """
    )
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_BOUNDSCHECK": "1", "NUMBA_CACHE_DIR": cache}
        checked = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600
        )
    assert checked.returncode == 0, checked.stderr[-2000:]
    here = subprocess.run(
        [sys.executable, "-c", code],
        env={k: v for k, v in os.environ.items() if k != "NUMBA_BOUNDSCHECK"},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert here.returncode == 0, here.stderr[-2000:]
    lik, q_sum, p1, p2 = json.loads(checked.stdout)
    assert [lik, q_sum, p1, p2] == json.loads(here.stdout)
    assert q_sum > 0 and all(np.isfinite(lik))
