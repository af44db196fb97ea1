"""The covariance stays symmetric positive definite over long, badly conditioned runs."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import ExtendedKalmanFilter, KalmanFilter, UnscentedKalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix, RangeBearing


@pytest.mark.parametrize("cls", [KalmanFilter, ExtendedKalmanFilter, UnscentedKalmanFilter])
def test_covariance_stays_symmetric_pd_over_500_badly_conditioned_steps(cls):
    """Huge prior (1e8), tiny process noise (q = 1e-9), a near-exact and strongly correlated
    position fix (eigenvalues 1e-10 and 2) next to a coarse radar: condition numbers ~1e18."""
    rng = np.random.default_rng(20)
    motion = ConstantVelocity(q=1e-9)
    fix_cov = np.array([[1.0, 1.0 - 1e-10], [1.0 - 1e-10, 1.0]])
    sensors = [
        PositionFix("fix", cov=fix_cov),
        RangeBearing("radar", position=[-50.0, 0.0], sigma_range=5.0, sigma_bearing=0.1),
    ]
    filt = cls(motion, sensors)
    belief = Gaussian(np.zeros(4), np.diag([1e8, 1e8, 1e4, 1e4]))
    x = np.array([3.0, -2.0, 0.5, 0.2])
    chol_fix = np.linalg.cholesky(fix_cov)
    worst = np.inf
    for k in range(500):
        dt = 0.01 if k % 2 else 1.0
        x = motion.mean(x, dt)
        belief = filt.predict(belief, dt)
        ms = [Measurement(k, "fix", x[:2] + chol_fix @ rng.standard_normal(2))]
        if k % 5 == 0:
            ms.append(Measurement(k, "radar", sensors[1].predict(x)))
        belief = filt.update(belief, ms)
        c = belief.cov
        assert np.array_equal(c, c.T), f"asymmetric at step {k}"
        assert np.all(np.isfinite(c)) and np.all(np.isfinite(belief.mean))
        np.linalg.cholesky(c)  # raises if not positive definite
        worst = min(worst, float(np.linalg.eigvalsh(c)[0]))
    assert worst > 0
    assert filt.stats.degenerate_steps == 0
