"""Any filter behind the tracker interface: stepping SingleTargetTracker scan by scan gives
run_filter's estimates exactly (one filter_step per scan, a predict only when time moves)."""

import numpy as np

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import KalmanFilter, run_filter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import LinearGaussianSensor
from fusetrack.tracking import SingleTargetTracker, Tracker


def test_single_target_tracker_equals_run_filter():
    kf = KalmanFilter(
        ConstantVelocity(ndim=1, q=0.3),
        [LinearGaussianSensor("pos", H=[[1.0, 0.0]], R=[[0.5]])],
    )
    prior = Gaussian(np.zeros(2), np.eye(2) * 4.0)
    rng = np.random.default_rng(5)
    times = np.cumsum(rng.uniform(0.2, 1.0, 12))
    ms = [Measurement(t, "pos", [np.sin(t) + rng.normal(0, 0.7)]) for t in times]
    tracker = SingleTargetTracker(kf, lambda _rng: prior, start=float(times[0]))
    assert isinstance(tracker, Tracker)
    state, means = tracker.initial_state(), []
    for m in ms:
        state = tracker.step(state, m.time, [m])
        (track,) = state.confirmed
        assert track.id == 0
        means.append(track.belief.mean)
    ref = run_filter(kf, prior, ms)
    np.testing.assert_allclose(np.array(means), ref.means, rtol=0, atol=1e-12)
