"""The best-possible rows of the Zhai 2007 reports (issue 19): statistics, verdicts, the PCRB of
a rank-deficient model, the posterior-mean bootstrap and the trivial estimators."""

import numpy as np
import pytest

from fusetrack.core import ConfigError, Gaussian
from fusetrack.evaluation import ClaimKinds
from fusetrack.experiments.zhai2007 import best_possible as bp
from fusetrack.experiments.zhai2007 import galerkin, scalar, sensor_network
from fusetrack.motion import ConstantVelocity, ScalarBenchmark
from fusetrack.sensors import Bearing, Power

KINDS = ClaimKinds({"BP_*": "diagnostic"})


def test_rms_over_runs_and_paper_rms_by_hand():
    value, se = bp.rms_over_runs([3.0, 4.0])  # mean of squares 12.5
    assert value == pytest.approx(np.sqrt(12.5))
    # s.e. of the mean of squares: std([9, 16], ddof=1) / sqrt(2) = 3.5; delta method / (2 root)
    assert se == pytest.approx(3.5 / (2 * np.sqrt(12.5)))
    assert bp.paper_rms(3.0, 16.0) == pytest.approx(5.0)


def test_verdict_and_claims_label_a_number_below_the_best_possible():
    assert bp.verdict(1.0, 2.0, 0.1) == bp.IMPOSSIBLE
    assert bp.verdict(1.75, 2.0, 0.1) == bp.POSSIBLE  # within 3 s.e.
    assert bp.verdict(3.0, 2.0, 0.1, bound=3.5) == bp.IMPOSSIBLE  # below the PCRB
    assert bp.verdict(1.0, 2.0, 0.1, model="z=x^2") == "impossible under 'z=x^2'"
    low = bp.possible_claim(KINDS, "BP_a", "row", 1.0, (2.0, 0.1), 0.5)
    assert not low.holds and bp.IMPOSSIBLE in low.ours and low.kind == "diagnostic"
    assert bp.possible_claim(KINDS, "BP_b", "row", 2.5, (2.0, 0.1)).holds
    far = bp.converged_claim(KINDS, "BP_c", "bootstrap", 1.18, ("cube root", 0.26))
    assert not far.holds and bp.NOT_FROM_MODEL in far.ours


def test_verdict_of_a_score_where_higher_is_better():
    """An ISNR above the best possible's (by more than 3 s.e.) is the impossible side."""
    assert bp.verdict(9.0, 8.0, 0.1, better="higher") == bp.IMPOSSIBLE
    assert bp.verdict(8.25, 8.0, 0.1, better="higher") == bp.POSSIBLE  # within 3 s.e.
    assert bp.verdict(3.0, 8.0, 0.1, better="higher") == bp.POSSIBLE  # below: merely worse
    high = bp.possible_claim(KINDS, "BP_d", "ISNR", 9.0, (8.0, 0.1), better="higher")
    assert not high.holds and "not above" in high.statement and "<=" in high.tolerance
    with pytest.raises(ConfigError, match="better"):
        bp.verdict(1.0, 2.0, 0.1, better="up")  # type: ignore[arg-type]


def test_pcrb_of_a_rank_deficient_cv_model_equals_the_linear_recursion():
    """CV with Gamma Q Gamma^T (rank 2) regularised by 1e-6 q against the exact linear-model
    recursion J' = (Q + F J^-1 F^T)^-1 + E[H^T R^-1 H] (Tichavsky et al. 1998, linear case)."""
    model = ConstantVelocity(q=0.05, noise="discrete")
    sensor = Bearing("s", position=[0.0, 0.0], sigma=0.1)
    p0 = np.diag([1.0, 1.0, 0.1, 0.1])
    rng = np.random.default_rng(1)
    x0 = rng.multivariate_normal([0.0, 50.0, 1.0, -1.0], p0, size=200)
    x = bp.simulate_many(lambda x, r: model.sample(x, 1.0, r), x0, 20, rng)
    got = bp.pcrb_rms(bp.Regularised(model, 1e-6 * 0.05), [sensor], x, 1.0, p0, [0])
    F, Q, J, want = model.jacobian(x[0, 0], 1.0), model.noise_cov(1.0), np.linalg.inv(p0), []
    for k in range(1, 21):
        J = np.linalg.inv(Q + F @ np.linalg.inv(J) @ F.T)
        J = J + sensor.fisher_information(x[:, k]).mean(axis=0)
        want.append(np.sqrt(np.linalg.inv(J)[0, 0]))
    assert got.shape == (20,)
    np.testing.assert_allclose(got, want, rtol=1e-5)


def test_posterior_mean_beats_the_trivial_estimator_on_the_scalar_model():
    """On Zhai's scalar model as printed the posterior mean is well below the cube root of each
    measurement (what makes Table 3's bootstrap levels impossible), and the PCRB below both."""
    motion, sensor = ScalarBenchmark(), Power("z", 3, 1.0)
    pm, cube = [], []
    for seed in range(6):
        truth, zs = scalar.simulate(motion, sensor, np.random.default_rng(seed))
        est, _ = bp.posterior_mean(
            motion,
            [sensor],
            Gaussian(np.zeros(1), np.eye(1)),
            zs,
            1.0,
            2000,
            np.random.default_rng([seed, 1]),
        )
        z = np.array([m[0] for m in zs])
        pm.append(np.sqrt(np.mean((est[:, 0] - truth[:, 0]) ** 2)))
        cube.append(np.sqrt(np.mean((scalar.invert(sensor, z)[:, 0] - truth[:, 0]) ** 2)))
    best, trivial = bp.rms_over_runs(pm)[0], bp.rms_over_runs(cube)[0]
    bound = scalar.pcrb(scalar.VARIANTS["printed"], 0, 300)
    assert bound < best < 0.75 * trivial < 1.18  # the paper's BS2000


def test_trivial_estimators_by_hand():
    even = Power("z", 2, 1.0, 0.5)
    np.testing.assert_allclose(scalar.invert(even, np.array([[2.0], [-1.0]])), [[2.0], [0.0]])
    cs = galerkin.comparator_scenario(1, 3)
    dr = galerkin.dead_reckoning(cs)
    np.testing.assert_allclose(dr[4], cs.motion.mean(cs.prior.mean, 5.0))


def test_triangulation_recovers_a_point_from_exact_bearings():
    """Exact bearings from the active sensors meet at the target (least squares, E4)."""
    target = np.array([120.0, 230.0])
    zs = [
        [
            np.array([np.arctan2(target[1] - p[1], target[0] - p[0])])
            if k in (13, 40, 77)
            else None
            for k, p in enumerate(sensor_network.GRID)
        ]
    ]
    cs = type("S", (), {"zs": zs, "prior": Gaussian(np.zeros(4), np.eye(4))})()
    est = sensor_network.triangulate(cs)  # type: ignore[arg-type]
    np.testing.assert_allclose(est[0, :2], target, atol=1e-9)
