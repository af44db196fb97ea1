"""P{eta_i = 1 | u} and P{eta_i = 1, eta_k = 1 | u} (Ercan et al. 2013, Eq. 8) per particle and
averaged: the kernels against the products written out in NumPy, and a hand-computed case."""

import numpy as np

from fusetrack.world import pair_visibility_kernel, pair_visibility_per_particle_kernel


def _numpy_terms(q: np.ndarray, assigned: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p1 = assigned * np.prod(np.clip(1.0 - q, 0.0, None), axis=-1)
    both = assigned[:, None, :] & assigned[None, :, :]
    p2 = both * np.prod(np.clip(1.0 - q[:, None] - q[None, :], 0.0, None), axis=-1)
    diag = np.arange(len(p1))
    p2[diag, diag] = p1
    return p1, p2


def _random_case(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    n, particles, m = 6, 50, 9
    q = rng.random((n, particles, m)) * 0.6  # large enough that some 1 - q_i - q_k < 0
    q[q < 0.25] = 0.0
    assigned = rng.random((n, particles)) < 0.7
    w = rng.random(particles)
    return q, assigned, w / w.sum()


def test_per_particle_terms_equal_the_numpy_products():
    for seed in range(3):
        q, assigned, _ = _random_case(seed)
        p1, p2 = pair_visibility_per_particle_kernel(q, assigned)
        e1, e2 = _numpy_terms(q, assigned)
        np.testing.assert_allclose(p1, e1, rtol=1e-13, atol=0)  # NumPy multiplies in another order
        np.testing.assert_allclose(p2, e2, rtol=1e-13, atol=0)
        assert (p2 == 0).any() and (p2[~np.eye(6, dtype=bool)] > 0).any()  # both regimes met


def test_averaged_kernel_is_the_weighted_sum_of_the_terms():
    q, assigned, w = _random_case(5)
    p1, p2 = pair_visibility_kernel(q, assigned, w)
    t1, t2 = pair_visibility_per_particle_kernel(q, assigned)
    np.testing.assert_allclose(p1, t1 @ w, rtol=1e-13)
    np.testing.assert_allclose(p2, t2 @ w, rtol=1e-13, atol=1e-16)


def test_one_particle_at_a_time_equals_the_terms_bit_for_bit():
    """The averaged kernel works a camera's pairs four at a time; with one particle of weight 1
    each of its sums is one term, which must equal the one-pair products exactly (12 cameras,
    so that most particles have blocks of four pairs and a remainder)."""
    rng = np.random.default_rng(11)
    q = rng.random((12, 40, 30)) * 0.12
    q[rng.random(q.shape) < 0.3] = 0.0
    q[:, :5, 3] = 0.7  # pairs whose factor 1 - q_i - q_k <= 0: products of 0
    assigned = rng.random((12, 40)) < 0.8
    t1, t2 = pair_visibility_per_particle_kernel(q, assigned)
    for l in range(40):
        p1, p2 = pair_visibility_kernel(q[:, l : l + 1], assigned[:, l : l + 1], np.ones(1))
        assert np.array_equal(p1, t1[:, l]) and np.array_equal(p2, t2[:, :, l])
    assert (t2 == 0).any() and (t2 > 0).any() and assigned.sum(0).max() >= 9


def test_hand_computed_pair():
    q = np.array([[[0.1, 0.2]], [[0.3, 0.5]]])  # 2 cameras, 1 particle, 2 occluders
    p1, p2 = pair_visibility_per_particle_kernel(q, np.ones((2, 1), dtype=bool))
    assert p1[:, 0].tolist() == [0.9 * 0.8, 0.7 * 0.5]
    assert p2[0, 1, 0] == p2[1, 0, 0] == (1 - 0.1 - 0.3) * max(1 - 0.2 - 0.5, 0.0)
    p1, p2 = pair_visibility_per_particle_kernel(q, np.array([[True], [False]]))
    assert p1[1, 0] == 0.0 and p2[0, 1, 0] == 0.0 and p2[0, 0, 0] == p1[0, 0]


def test_from_the_priors_equals_the_kernel_on_the_q_array_bit_for_bit():
    """Camera selection's one-pass kernel (q one particle at a time, only on assigned cameras)
    against the two-step path it replaces (q of every triple, then the pair kernel): identical
    values, isotropic and correlated priors, with and without the shortened rectangles, points at
    a camera (empty rectangle) included."""
    from fusetrack.world import OccluderPriors, occlusion_probability
    from fusetrack.world.occlusion_kernels import pair_visibility_of_priors_kernel

    rng = np.random.default_rng(11)
    cams = np.array([[0.0, 0.0], [50.0, 0.0], [50.0, 50.0], [0.0, 50.0], [25.0, 0.0]])
    for trial in range(6):
        x = rng.uniform(10, 40, 2) + rng.normal(0, [0.5, 3.0, 9.0][trial % 3], (300, 2))
        x[0] = cams[1]
        mu = rng.uniform(0, 50, (25, 2))
        if trial % 2:
            a = rng.normal(0, 1, (25, 2, 2))
            cov = a @ np.swapaxes(a, 1, 2) * 4.0 + 0.1 * np.eye(2)
        else:
            cov = np.broadcast_to(np.eye(2) * rng.choice([0.5, 30.0, 120.0]), (25, 2, 2))
        priors = OccluderPriors(mu, cov)
        exclusion = 3.33 * (trial // 3)
        assigned = rng.random((len(cams), len(x))) < 0.6
        w = rng.random(len(x))
        q = occlusion_probability(cams, x, priors, 3.33, exclusion)
        two_step = pair_visibility_kernel(q, assigned, w)
        one_pass = pair_visibility_of_priors_kernel(
            cams, x, priors.mean, np.ascontiguousarray(priors.cov), 3.33, exclusion, assigned, w
        )
        assert np.all(q[1, 0] == 0.0) and 0.0 < two_step[1][0, 2] < two_step[0][0]
        for a_, b_ in zip(two_step, one_pass, strict=True):
            assert np.array_equal(a_, b_)
