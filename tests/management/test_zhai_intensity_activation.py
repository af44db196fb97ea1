"""Power-aware activation by received intensity and the dB intensity sensor (Zhai 2007, Eq. 37, Table 4)."""

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters.cpf_sp import CPFSPProposal
from fusetrack.filters.sis import ProposalParticleFilter, sensor_measurements
from fusetrack.management.intensity_activation import (
    activation_radius,
    active_sensors,
    intensity_weights,
)
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing
from fusetrack.sensors.acoustic_intensity import AcousticIntensity


def test_activation_radii_of_the_spec():
    """Spec Sec. 4, E4: 91.2, 56.2 and 34.7 m for 72, 75 and 78 % of 70 dB."""
    assert [round(activation_radius(t, 70.0), 1) for t in (0.72, 0.75, 0.78)] == [91.2, 56.2, 34.7]


def test_active_sensors_and_weights_by_hand():
    levels = np.array([60.0, 52.0, np.nan, 53.0])
    act = active_sensors(levels, 0.75, 70.0)  # threshold 52.5 dB
    assert act.tolist() == [True, False, False, True]
    w = intensity_weights(levels, act)
    p = 10 ** (np.array([60.0, 53.0]) / 10)
    np.testing.assert_allclose(w[[0, 3]], p / p.sum())
    assert w[1] == w[2] == 0.0
    assert np.all(intensity_weights(levels, np.zeros(4, bool)) == 0)
    with pytest.raises(ValueError, match="threshold"):
        active_sensors(levels, 1.5, 70.0)


def test_intensity_sensor_level_and_jacobian():
    s = AcousticIntensity("m", position=[1.0, 2.0], source_db=70.0, alpha=4.0)
    x = np.array([4.0, 6.0, 0.0, 0.0])  # d = 5
    assert s.predict(x)[0] == pytest.approx(70.0 - 20.0 * np.log10(5.0))
    eps = 1e-6
    num = [(s.predict(x + eps * e)[0] - s.predict(x - eps * e)[0]) / (2 * eps) for e in np.eye(4)]
    np.testing.assert_allclose(s.jacobian(x)[0], num, atol=1e-6)
    with pytest.raises(ValueError, match="position"):
        AcousticIntensity("m", position=[0.0, 0.0, 0.0])


def test_cpf_sp_tracks_with_two_sensors_and_handles_silent_steps():
    """Two bearing sensors triangulate; a step with no active sensor falls back to the prior."""
    motion = ConstantVelocity(q=0.05)
    sensors = [
        Bearing("a", position=[0.0, 0.0], sigma=0.02),
        Bearing("b", position=[40.0, 0.0], sigma=0.02),
    ]
    rng = np.random.default_rng(0)
    truth = [np.array([10.0 + k, 20.0, 1.0, 0.0]) for k in range(1, 16)]
    zs = [[s.simulate(x, rng) for s in sensors] for x in truth]
    zs[7] = [None, None]
    aux = [np.array([0.5, 0.5])] * 15
    f = ProposalParticleFilter(motion, sensors, CPFSPProposal(5), 300, transition="marginal")
    prior = Gaussian(np.array([10.0, 20.0, 1.0, 0.0]), np.diag([4.0, 4.0, 0.1, 0.1]))
    b, est = f.initialize(prior, rng), []
    for k, (step, w) in enumerate(zip(zs, aux)):
        ms = [
            *sensor_measurements(sensors, step, k + 1.0),
            Measurement(k + 1.0, "sensor-weights", w),
        ]
        b = f.step(b, 1.0, ms, rng)
        est.append(b.mean)
    est = np.array(est)
    err = np.hypot(*(est[:, :2] - np.array(truth)[:, :2]).T)
    assert np.all(np.isfinite(est)) and err[-5:].mean() < 2.0
