"""The waypoint-regime particle dynamics of Ercan et al. 2013 (Sec. 4.1, Eq. 5)."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.motion.waypoint_regime import WaypointRegimeDynamics


def far_particles(n):
    u = np.zeros((n, 5))
    u[:, 2:4] = [100.0, 0.0]  # destination far to the east
    u[:, 4] = 1.0
    return u


def sampler(rng, n):
    return rng.uniform(0, 100, (n, 2))


def test_regime_probabilities_and_step_length_when_moving():
    dyn = WaypointRegimeDynamics(sigma_v=0.0)
    u = far_particles(20000)
    new = dyn.sample(u, np.random.default_rng(0), sampler)
    moved = np.hypot(*(new[:, :2] - u[:, :2]).T)
    changed = np.any(new[:, 2:4] != u[:, 2:4], axis=1)
    assert np.mean(moved == 0) == pytest.approx(0.05, abs=0.01)  # wait
    assert np.mean(changed) == pytest.approx(0.05, abs=0.01)  # change destination
    mtd = ~changed & (moved > 0)
    assert np.allclose(new[mtd, :2], [1.0, 0.0])  # one speed-length step toward the destination
    assert np.allclose(moved[moved > 0], 1.0)
    assert np.allclose(new[mtd, 4], 1.0)  # s = 0.3 s + 0.7 |step|


def test_reached_destination_mostly_changes_it():
    dyn = WaypointRegimeDynamics()
    u = far_particles(20000)
    u[:, 2:4] = [0.5, 0.0]  # within one speed of the destination
    new = dyn.sample(u, np.random.default_rng(1), sampler)
    assert np.mean(np.any(new[:, 2:4] != u[:, 2:4], axis=1)) == pytest.approx(0.9, abs=0.01)


def test_speed_update_and_mean_point():
    dyn = WaypointRegimeDynamics(sigma_v=0.33)
    u = far_particles(5)
    u[:, 4] = 2.0
    kappa = dyn.mean(u)
    assert np.allclose(kappa[:, :2], [2.0, 0.0]) and np.allclose(kappa[:, 2:], u[:, 2:])
    u[:, 2:4] = [1.0, 0.0]  # reached: kappa stays
    assert np.allclose(dyn.mean(u)[:, :2], 0.0)


def test_moves_out_of_free_space_are_rejected():
    dyn = WaypointRegimeDynamics(sigma_v=0.0, beta_moving=1.0, lambda_moving=0.0)
    u = far_particles(10)
    new = dyn.sample(u, np.random.default_rng(2), sampler, free=lambda p: p[:, 0] < 0.5)
    assert np.allclose(new[:, :2], 0.0)


def test_invalid_regime_probabilities():
    with pytest.raises(ConfigError):
        WaypointRegimeDynamics(beta_moving=0.9, lambda_moving=0.2)
    with pytest.raises(ConfigError):
        WaypointRegimeDynamics(sigma_v=-1.0)


@pytest.mark.parametrize("sigma_v", [0.0, 0.33])
def test_numba_sample_equals_the_numpy_reference(sigma_v):
    """Same random draws, same particles, bit for bit: a mix of moving, reached, waiting and
    destination-changing particles, some of whose moves leave the free floor."""
    dyn = WaypointRegimeDynamics(sigma_v=sigma_v)
    rng = np.random.default_rng(5)
    u = np.empty((3000, 5))
    u[:, :2] = rng.uniform(0, 100, (3000, 2))
    u[:, 2:4] = u[:, :2] + rng.normal(0, 3, (3000, 2))
    u[:5, 2:4] = u[:5, :2]  # standing on the destination
    u[:, 4] = rng.uniform(0.2, 2.0, 3000)

    def free(p):
        return (p[:, 0] > 2) & (p[:, 0] < 98) & ~((np.abs(p[:, 0] - 50) < 10) & (p[:, 1] < 40))

    fast = dyn.sample(u, np.random.default_rng(9), sampler, free)
    ref = dyn.sample_reference(u, np.random.default_rng(9), sampler, free)
    assert np.array_equal(fast, ref)
    assert not np.array_equal(fast[:, :2], u[:, :2])


def test_numba_mean_equals_the_numpy_reference():
    """kappa bit for bit: moving particles, reached ones (they stay), one on its destination and
    one with zero speed."""
    dyn = WaypointRegimeDynamics()
    rng = np.random.default_rng(6)
    u = np.empty((2000, 5))
    u[:, :2] = rng.uniform(0, 100, (2000, 2))
    u[:, 2:4] = u[:, :2] + rng.normal(0, 3, (2000, 2))
    u[:, 4] = rng.uniform(0.2, 4.0, 2000)
    u[0, 2:4] = u[0, :2]
    u[1, 4] = 0.0
    kappa = dyn.mean(u)
    assert np.array_equal(kappa, dyn.mean_reference(u))
    reached = np.hypot(*(u[:, 2:4] - u[:, :2]).T) < u[:, 4]
    assert 0 < reached.sum() < len(u)  # both regimes present
    assert np.array_equal(kappa[reached], u[reached])
    assert not np.array_equal(dyn.mean(u[::2]), u[::2])  # strided input
