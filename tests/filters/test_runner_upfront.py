"""run_filter checks every measurement before doing any work."""

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement, MeasurementError, UnknownSensorError
from fusetrack.filters import ExtendedKalmanFilter, run_filter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing


class CountingEKF(ExtendedKalmanFilter):
    calls = 0

    def predict(self, belief, dt, rng=None):
        CountingEKF.calls += 1
        return super().predict(belief, dt, rng)


@pytest.mark.parametrize(
    ("bad", "error", "text"),
    [
        (Measurement(5.0, "radar", [1.0]), UnknownSensorError, "radar"),
        (Measurement(5.0, "mic", [1.0, 2.0]), MeasurementError, "m=1"),
    ],
)
def test_bad_measurement_late_in_the_stream_fails_before_any_step(bad, error, text):
    ekf = CountingEKF(ConstantVelocity(), [Bearing("mic", position=[0.0, 0.0], sigma=0.01)])
    good = [Measurement(t, "mic", [0.3]) for t in (1.0, 2.0, 3.0)]
    CountingEKF.calls = 0
    with pytest.raises(error, match=text):
        run_filter(ekf, Gaussian(np.ones(4), np.eye(4)), [*good, bad], t0=0.0)
    assert CountingEKF.calls == 0
