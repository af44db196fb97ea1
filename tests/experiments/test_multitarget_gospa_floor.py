"""The oracle floor of ``multitarget-bearings`` and ``multitarget-benchmark``
(multitarget/gospa_floor.py): Eq. (1) against the GOSPA implementation, Eq. (2) by hand and by
Monte Carlo, the position bounds by hand, the whole-run bound against the inverse of the whole
path's information."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.evaluation import gospa
from fusetrack.experiments.multitarget.gospa_floor import (
    bearing_oracle,
    entry_prior_cov,
    smoothed_bounds,
    states,
    truncated_square_floor,
)
from fusetrack.experiments.multitarget.scenario import Scene, make_scene
from fusetrack.filters import GridSpec

C = 3.0


def test_eq1_bounds_gospa_of_any_estimate_set():
    """d^2 >= sum_i min(D_i^2, c^2/2) + c^2/2 max(m - n, 0) on random sets of every size."""
    rng = np.random.default_rng(0)
    for _ in range(300):
        n, m = rng.integers(0, 5, 2)
        truth = rng.uniform(0, 8, (n, 2))
        est = rng.uniform(0, 8, (m, 2))
        d2 = gospa(est, truth, c=C).distance ** 2
        if n and m:
            nearest = np.linalg.norm(truth[:, None] - est[None], axis=-1).min(axis=1)
        else:
            nearest = np.full(n, np.inf)
        floor = np.minimum(nearest**2, C**2 / 2).sum() + C**2 / 2 * max(m - n, 0)
        assert d2 >= floor - 1e-9


def test_eq2_by_hand_and_monte_carlo():
    B = np.diag([0.5, 0.25])
    # tr B = 0.75, tr B^2 = 0.3125: 0.75 - (0.5625 + 0.625) / (4 * 2) = 0.6015625
    assert truncated_square_floor(B, 2.0) == pytest.approx(0.6015625, abs=1e-12)
    g = np.random.default_rng(1).multivariate_normal([0, 0], B, 400_000)
    mc = np.minimum(np.sum(g**2, axis=1), 2.0).mean()  # ~0.66, s.e. ~0.001
    assert 0.6015625 <= mc <= 0.75
    # a wide error: the quadratic lower bound goes negative and is clipped
    assert truncated_square_floor(4.0 * np.eye(2), 2.0) == 0.0
    # small errors: the truncation hardly matters
    assert truncated_square_floor(0.01 * np.eye(2), C**2 / 2) == pytest.approx(0.02 - 0.0008 / 18)


def _scene(arrays: tuple[tuple[str, float, float], ...]) -> Scene:
    return Scene(GridSpec(-20.0, 20.0, -20.0, 20.0, 0.5), arrays, 0.1, 0.9, 0.0, 0.25)


def test_one_scan_bound_by_hand():
    """Arrays 10 m west and 10 m south of the target: each bearing informs one axis with
    P_D / (sigma r)^2 = 0.9 / (0.1 * 10)^2 = 0.9; with a unit prior the bound is 1 / 1.9 I."""
    scene = _scene((("w", -10.0, 0.0), ("s", 0.0, -10.0)))
    online, whole = bearing_oracle(scene).position_bounds(np.zeros((1, 4)), np.eye(4))
    np.testing.assert_allclose(online[0], np.eye(2) / 1.9, atol=1e-12)
    np.testing.assert_allclose(whole[0], online[0], atol=1e-12)


def test_whole_run_bound_is_the_information_of_every_scan():
    """No process noise: the state at scan 0 is seen at scan 1 through F, so its whole-run
    information is P_0^-1 + I_0 + F^T I_1 F; online at scan 1 it is F^-T (P_0^-1 + I_0) F^-1 + I_1."""
    scene = _scene((("w", -10.0, 0.0), ("s", 0.0, -10.0)))
    x = np.array([[0.0, 0.0, 4.0, 0.0], [1.0, 0.0, 4.0, 0.0]])
    F = np.eye(4)
    F[0, 2] = F[1, 3] = 0.25

    def info(p):  # 0.9 H^T H / sigma^2 per array, H = [-d_y, d_x] / r^2 on the position
        J = np.zeros((4, 4))
        for _, sx, sy in scene.arrays:
            d = p - np.array([sx, sy])
            h = np.array([-d[1], d[0], 0.0, 0.0]) / (d @ d)
            J += 0.9 * np.outer(h, h) / 0.1**2
        return J

    J0 = np.eye(4) + info(x[0, :2])
    online, whole = bearing_oracle(scene).position_bounds(x, np.eye(4))
    Fi = np.linalg.inv(F)
    np.testing.assert_allclose(online[1], np.linalg.inv(Fi.T @ J0 @ Fi + info(x[1, :2]))[:2, :2])
    np.testing.assert_allclose(whole[0], np.linalg.inv(J0 + F.T @ info(x[1, :2]) @ F)[:2, :2])
    np.testing.assert_allclose(whole[1], online[1], atol=1e-12)
    assert np.trace(whole[0]) < np.trace(online[0])  # later bearings can only help


def test_entry_prior_spread_is_the_model_draws():
    """A target's first height is uniform on [3, 17] m: std 14 / sqrt(12) = 4.04 m."""
    P = entry_prior_cov(make_scene(2, 2.0, 0.9, 0.5), 2, 14.0)
    assert P.shape == (2, 4, 4)
    assert np.sqrt(P[:, 1, 1]) == pytest.approx(14 / np.sqrt(12), rel=0.03)
    on, x = states(np.array([[np.nan, np.nan], [1.0, 2.0], [2.0, 2.5]]), 0.25)
    assert on.tolist() == [1, 2]
    np.testing.assert_allclose(x[:, 2:], [[4.0, 2.0], [4.0, 2.0]])


def test_whole_run_bound_is_the_inverse_of_the_whole_path_information():
    """With process noise the whole-run bound at each scan is the diagonal block of the inverse of
    the path's block-tridiagonal information (prior, motion, measurements), built by hand."""
    rng = np.random.default_rng(3)
    d, T = 2, 4
    F = np.array([[1.0, 0.5], [0.0, 1.0]])
    Q = np.array([[0.2, 0.1], [0.1, 0.3]])
    I_k = [np.diag(rng.uniform(0.1, 2.0, d)) for _ in range(T)]
    P0 = np.diag([4.0, 1.0])
    # online bounds: the Kalman covariance recursion with measurement information I_k
    online = [np.linalg.inv(np.linalg.inv(P0) + I_k[0])]
    for k in range(1, T):
        online.append(np.linalg.inv(np.linalg.inv(F @ online[-1] @ F.T + Q) + I_k[k]))
    Qi = np.linalg.inv(Q)
    J = np.zeros((d * T, d * T))
    J[:d, :d] = np.linalg.inv(P0)
    for k in range(T):
        J[k * d : (k + 1) * d, k * d : (k + 1) * d] += I_k[k]
    for k in range(T - 1):
        a, b = slice(k * d, (k + 1) * d), slice((k + 1) * d, (k + 2) * d)
        J[a, a] += F.T @ Qi @ F
        J[b, b] += Qi
        J[a, b] -= F.T @ Qi
        J[b, a] -= Qi @ F
    full = np.linalg.inv(J)
    S = smoothed_bounds(np.array(online), F, Q)
    for k in range(T):
        np.testing.assert_allclose(S[k], full[k * d : (k + 1) * d, k * d : (k + 1) * d], rtol=1e-10)
    np.testing.assert_allclose(S[-1], online[-1])
