"""SP-PEKF bank and PF-SP-PEKF (Zhai 2007, Ch. 3) against the Kalman filter on linear models."""

import numpy as np
import pytest

from fusetrack.core import Filter, Gaussian, Measurement
from fusetrack.core.errors import UnknownSensorError
from fusetrack.filters import KalmanFilter, run_filter
from fusetrack.filters.sis import ProposalParticleFilter
from fusetrack.filters.sp_pekf import (
    BankState,
    SPPEKFBank,
    SPPEKFProposal,
    gaussian_draw,
    gaussian_draw_rows,
    repair_covariance,
)
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix


def _linear():
    motion = ConstantVelocity(ndim=1, q=0.5)
    sensor = PositionFix("p", cov=[[0.8]], position_index=(0,))
    prior = Gaussian(np.array([1.0, -0.5]), np.diag([2.0, 0.7]))
    return motion, sensor, prior


def test_every_channel_is_the_kalman_filter_on_a_linear_model():
    """Linear f, h: x_n + x_r follows the KF exactly whatever the nominal noise (Eqs. 18-27)."""
    motion, sensor, prior = _linear()
    bank = SPPEKFBank(motion, [sensor], n_channels=5)
    rng = np.random.default_rng(3)
    nominal = prior.mean + rng.standard_normal((5, 2))  # arbitrary partition of the same mean
    state = BankState(
        nominal,
        prior.mean - nominal,
        np.broadcast_to(prior.cov, (5, 2, 2)).copy(),
        np.zeros(5),
        prior.mean,
        prior.cov,
    )
    kf = KalmanFilter(motion, [sensor])
    belief = prior
    for k, z in enumerate([1.3, 0.2, -0.8, 2.5]):
        state = bank.update(bank.predict(state, 1.0, rng), [Measurement(float(k), "p", [z])])
        belief = kf.update(kf.predict(belief, 1.0), [Measurement(float(k), "p", [z])])
        np.testing.assert_allclose(
            state.nominal + state.resid, np.tile(belief.mean, (5, 1)), atol=1e-9
        )
        np.testing.assert_allclose(state.cov[0], belief.cov, atol=1e-9)
        np.testing.assert_allclose(state.total_cov, belief.cov, atol=1e-9)  # channels agree
        np.testing.assert_allclose(np.exp(state.log_psi), 0.2, atol=1e-12)


def test_pf_sp_pekf_mean_converges_to_the_kalman_mean():
    """The proposal changes only the variance, not the posterior: 400 runs, mean error < 4 s.e."""
    motion, sensor, prior = _linear()
    rng = np.random.default_rng(0)
    zs = [[np.array([z])] for z in (0.9, 1.4, 0.3, -0.2, 0.6)]
    kf = KalmanFilter(motion, [sensor])
    belief = prior
    for k, (z,) in enumerate(zs):
        belief = kf.update(kf.predict(belief, 1.0), [Measurement(float(k), "p", z)])
    pf = ProposalParticleFilter(motion, [sensor], SPPEKFProposal(n_channels=10), n_particles=300)
    ms = [Measurement(k + 1.0, "p", z) for k, (z,) in enumerate(zs)]
    final = run_filter(pf, pf.initialize(prior, rng, (400,)), ms, rng=rng, t0=0.0).means[-1]
    err = final.mean(axis=0) - belief.mean
    se = final.std(axis=0) / np.sqrt(len(final))
    assert np.all(np.abs(err) < 4 * se + 1e-3), (err, se)
    # and each run is close to the KF mean (proposal weights are correct, not just unbiased)
    assert np.sqrt(np.mean((final - belief.mean) ** 2, axis=0))[0] < 0.25 * np.sqrt(
        belief.cov[0, 0]
    )


def test_a_non_positive_definite_channel_is_repaired_and_counted():
    bad = np.array([[[1.0, 2.0], [2.0, 1.0]], [[2.0, 0.0], [0.0, 1.0]]])
    fixed, mask = repair_covariance(bad)
    assert mask.tolist() == [True, False]
    assert np.all(np.linalg.eigvalsh(fixed) > 0)
    np.testing.assert_array_equal(fixed[1], bad[1])


def test_a_channel_with_nan_is_dropped_not_propagated():
    motion, sensor, prior = _linear()
    bank = SPPEKFBank(motion, [sensor], n_channels=3)
    rng = np.random.default_rng(1)
    state = bank.initialize(prior, rng)
    resid = state.resid.copy()
    resid[1] = np.nan
    state = BankState(state.nominal, resid, state.cov, state.log_psi, state.mean, state.total_cov)
    out = bank.update(bank.predict(state, 1.0, rng), [Measurement(1.0, "p", [0.5])])
    assert bank.stats.dropped_channels == 1
    assert np.all(np.isfinite(out.mean)) and np.all(np.isfinite(out.total_cov))
    assert np.exp(out.log_psi[1]) < 1e-200


@pytest.mark.parametrize("n_channels", [0, 2.5, True])
def test_bank_refuses_bad_channel_counts(n_channels):
    motion, sensor, _ = _linear()
    with pytest.raises(ValueError, match="n_channels"):
        SPPEKFBank(motion, [sensor], n_channels=n_channels)


def test_the_bank_is_a_filter_and_predict_carries_the_channel_weights():
    """predict draws the nominal noise (the only draw), update weights the channels; a sensor the
    bank does not have is refused; silence leaves the memoryless weights equal."""
    motion, sensor, prior = _linear()
    bank = SPPEKFBank(motion, [sensor], n_channels=4)
    assert isinstance(bank, Filter)
    state = bank.initialize(prior, np.random.default_rng(0))
    pred = bank.predict(state, 1.0, np.random.default_rng(1))
    again = bank.predict(state, 1.0, np.random.default_rng(1))
    np.testing.assert_array_equal(pred.nominal, again.nominal)
    np.testing.assert_allclose(np.exp(pred.log_psi), 0.25, atol=1e-12)
    np.testing.assert_allclose(pred.mean, (pred.nominal + pred.resid).mean(axis=0), atol=1e-12)
    silent = bank.update(pred, [])
    np.testing.assert_allclose(silent.mean, pred.mean, atol=1e-12)
    with pytest.raises(UnknownSensorError, match="sensor_id"):
        bank.update(pred, [Measurement(1.0, "nobody", [0.0])])


@pytest.mark.parametrize("batch", [(), (3,)])
def test_drawing_chosen_rows_gives_those_rows_of_the_full_draw(batch):
    """gaussian_draw_rows (MMPF-SP: each particle drawn from its own regime's bank only) returns
    exactly the chosen rows of gaussian_draw and leaves the generator where it leaves it."""
    rng = np.random.default_rng(0)
    a = rng.normal(size=(*batch, 4, 4))
    cov = a @ np.swapaxes(a, -1, -2) + np.eye(4)
    mean = rng.normal(size=(*batch, 4))
    rows = rng.random((*batch, 200)) < 0.3
    full, g_full = gaussian_draw(mean, cov, 200, np.random.default_rng(5)), np.random.default_rng(5)
    g_rows = np.random.default_rng(5)
    x, log_q = gaussian_draw_rows(mean, cov, rows, g_rows)
    gaussian_draw(mean, cov, 200, g_full)
    assert x.shape == (rows.sum(), 4)
    np.testing.assert_array_equal(x, full[0][rows])
    np.testing.assert_array_equal(log_q, full[1][rows])
    assert g_rows.random() == g_full.random()
