"""The bounds' ``jacobians=`` option: precomputed transition Jacobians stand in for
``motion.jacobian`` (a motion whose model changes at known steps), checked before any work."""

import numpy as np
import pytest

from fusetrack.core import ConfigError, ShapeError
from fusetrack.evaluation import deterministic_crlb, posterior_crlb
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing

MIC = [Bearing("m", position=[0.0, 0.0], sigma=0.03)]
P0 = np.diag([1.0, 1.0, 0.1, 0.1])


def _truth(T=12, dt=1.0):
    cv = ConstantVelocity(ndim=2, q=0.2)
    x = np.zeros((T, 4))
    x[0] = [20.0, 5.0, -0.5, 0.8]
    for k in range(T - 1):
        x[k + 1] = cv.mean(x[k], dt)
    return cv, x


def test_given_jacobians_equal_the_motions():
    cv, x = _truth()
    F = np.broadcast_to(cv.jacobian(x[0], 1.0), (len(x) - 1, 4, 4))
    for bound in (posterior_crlb, deterministic_crlb):
        np.testing.assert_array_equal(
            bound(cv, MIC, x, 1.0, P0, jacobians=F), bound(cv, MIC, x, 1.0, P0)
        )


def test_given_jacobians_replace_the_motions():
    """A turn's Jacobian at one step (not what the constant-velocity motion says) changes the
    bound from that step on, and equals a motion that is the turn throughout for one step."""
    cv, x = _truth(T=3)
    c, s = np.cos(0.3), np.sin(0.3)
    Fct = np.eye(4)
    Fct[0, 2] = Fct[1, 3] = 1.0
    Fct[2:, 2:] = [[c, -s], [s, c]]  # the velocity turns by 0.3 rad in the step
    F = np.stack([Fct, cv.jacobian(x[1], 1.0)])
    got = deterministic_crlb(cv, MIC, x, 1.0, P0, jacobians=F)
    J0 = np.linalg.inv(P0) + MIC[0].fisher_information(x[0])
    Fi = np.linalg.inv(Fct)
    J1 = Fi.T @ J0 @ Fi + MIC[0].fisher_information(x[1])
    np.testing.assert_allclose(got[1], np.linalg.inv(J1), rtol=1e-10)
    assert not np.allclose(got[1], deterministic_crlb(cv, MIC, x, 1.0, P0)[1])


def test_bad_jacobians_are_named():
    cv, x = _truth()
    with pytest.raises(ShapeError, match=r"jacobians\.shape"):
        deterministic_crlb(cv, MIC, x, 1.0, P0, jacobians=np.eye(4)[None].repeat(3, 0))
    bad = np.broadcast_to(np.eye(4), (len(x) - 1, 4, 4)).copy()
    bad[2, 0, 0] = np.nan
    with pytest.raises(ConfigError, match="jacobians"):
        posterior_crlb(cv, MIC, x, 1.0, P0, jacobians=bad)
