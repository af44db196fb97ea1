"""Nott 2009's PCRB (issue 19): the tag-only bound is the Kalman filter's covariance on the
true model, the camera's information is D^T R^-1 D of its numerical Jacobian, the mean-error
bound is E|N(0, C)|, and the joint EKF's RMS in a few runs is not below the bound."""

import numpy as np
import pandas as pd
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.evaluation import ClaimKinds, run_monte_carlo
from fusetrack.experiments.nott2009 import best_possible as bp
from fusetrack.experiments.nott2009.scenario import SimConfig, run_once, simulate_truth
from fusetrack.experiments.nott2009.simulation import BURN_IN, configs
from fusetrack.filters import KalmanFilter, run_filter

KINDS = ClaimKinds({"BP_*": "diagnostic"})


def test_tag_only_bound_is_the_kalman_filter_covariance_on_the_true_model():
    """Camera blind throughout, tag every 2nd frame: a linear-Gaussian model (rank-2 Wiener
    noise, constant height and width), so the PCRB is exactly the KF's covariance."""
    cfg = SimConfig(dynamics="ca", n_steps=30, occ_start=0, occ_len=30, rfid_every=2)
    assert not bp.report_mask(cfg)[:, 1].any()
    x = bp.truths(cfg, [1, 2, 3])
    tag = bp.bound_sensors(cfg)[0]
    kf = KalmanFilter(bp.truth_motion(cfg), {"tag": tag})
    zs = x[0, :, :2] + np.random.default_rng(0).normal(size=(30, 2))
    ms = [Measurement(float(t), "tag", z) for t, z in zip(cfg.times, zs)][::2]
    track = run_filter(kf, Gaussian(x[0, 0], bp.PRIOR_COV), ms, times=cfg.times, t0=0.0)
    assert track.covariances is not None
    np.testing.assert_allclose(
        bp.position_bound(cfg, x), track.covariances[:, :2, :2], rtol=1e-9, atol=1e-14
    )


@pytest.mark.parametrize("variant", ["corners", "head_foot"])
def test_camera_information_is_that_of_its_numerical_jacobian(variant):
    cfg = SimConfig(variant=variant)
    cam = bp.bound_sensors(cfg)[1]
    x = simulate_truth(cfg, np.random.default_rng(4))[::7]
    D = np.empty((len(x), cam.dim, 6))
    for i in range(6):
        e = np.zeros(6)
        e[i] = 1e-6
        D[..., i] = (cam.predict(x + e) - cam.predict(x - e)) / 2e-6
    want = np.swapaxes(D, -1, -2) @ np.linalg.solve(cam.noise_cov(), D)
    scale = np.abs(want).max()  # central differences: ~1e-10 of the largest entry
    np.testing.assert_allclose(cam.fisher_information(x), want, rtol=1e-6, atol=1e-8 * scale)


def test_expected_norm_of_a_gaussian():
    s = 0.3
    assert bp.expected_norm(s**2 * np.eye(2)) == pytest.approx(s * np.sqrt(np.pi / 2), rel=1e-12)
    assert bp.expected_norm(np.diag([s**2, 0.0])) == pytest.approx(s * np.sqrt(2 / np.pi))
    C = np.array([[0.5, 0.2], [0.2, 0.15]])
    e = np.random.default_rng(1).multivariate_normal([0, 0], C, size=400_000)
    norms = np.linalg.norm(e, axis=1)
    assert abs(bp.expected_norm(C) - norms.mean()) < 3 * norms.std() / np.sqrt(len(norms))


@pytest.fixture(scope="module")
def few_runs():
    """Eight runs of three cases (no occlusion, a long one, a sparse tag in a long one)."""
    cases = [c for c in configs() if c["case"] in ("S1", "S4-ca", "rate-k5")]
    return cases, run_monte_carlo(run_once, cases, 8, 0, workers=1, progress=False)


def test_joint_ekf_is_not_below_the_bound(few_runs):
    cases, df = few_runs
    bounds = bp.estimate(df, cases, BURN_IN)
    assert set(bounds) == {"S1", "S4-ca", "rate-k5"}
    assert bounds["S4-ca"].spans == ["run", "window"] and bounds["S1"].spans == ["run"]
    claims = bp.above_claims(KINDS, bounds)
    assert [c.holds for c in claims] == [True] * 3, [(c.id, c.ours) for c in claims]
    for cb in bounds.values():
        for span in cb.spans:  # no tracker beats the bound by more than noise
            for m, (value, se) in cb.rms[span].items():
                assert value >= cb.bound.rms[span] - 3 * se, (cb.case, span, m)
    # less information, a larger bound: the tag every 5th frame in the same occlusion
    assert bounds["rate-k5"].bound.rms["window"] > bounds["S4-ca"].bound.rms["window"]
    assert bp.prior_claim(KINDS, bounds).holds  # S1 is checked


def test_claims_can_fail(few_runs):
    cases, df = few_runs
    bounds = bp.estimate(df, cases, BURN_IN)
    cb = bounds["S1"]
    better = {**cb.rms, "run": {**cb.rms["run"], "J": (0.5 * cb.bound.rms["run"], 1e-4)}}
    fake = bp.CaseBound("S1", cb.bound, better, cb.mean)
    assert not bp.above_claims(KINDS, {"S1": fake})[0].holds
    low = 0.9 * cb.bound.mean["run"]
    rows = bp.proto_rows({"S1": cb}, {"S1": {"J": low, "B1": 0.632}})
    assert list(rows["verdict"]) == [bp.IMPOSSIBLE, bp.POSSIBLE]
    (claim,) = bp.proto_claims(KINDS, rows)
    assert claim.id == "BP_PROTO_J_possible_S1" and not claim.holds


def test_truths_must_be_the_runs_own(few_runs):
    cases, df = few_runs
    bad = df.copy()
    bad.loc[(bad["case"] == "S1") & (bad["step"] == 3), "true_x"] += 1e-6
    with pytest.raises(RuntimeError, match="re-simulated truths"):
        bp.estimate(pd.DataFrame(bad), cases, BURN_IN)
