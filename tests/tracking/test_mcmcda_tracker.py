"""MCMCDA behind the trackers' interface: Measurements of position sensors in, live tracks and
Tracks with persistent ids out; bad input is a clear error or a counted skip."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.association import MCMCDAConfig
from fusetrack.core import ConfigError, Measurement, MeasurementError, UnknownSensorError
from fusetrack.sensors import LinearGaussianSensor, PositionFix, RangeBearing
from fusetrack.tracking import MCMCDATracker, MCMCDATrackerState

TAG = PositionFix("tag", cov=0.09 * np.eye(2))
# a sensor reporting the position shifted by (1, -2): its position is z - (1, -2)
OFFSET = np.array([1.0, -2.0])
CONFIG = MCMCDAConfig(n_mc=300, obs_std=0.3)
STARTS = [np.array([2.0, 8.0]), np.array([33.0, 12.0])]
VELS = [np.array([10.0, 0.5]), np.array([-10.0, -0.5])]


def scenario(n_steps=14):
    """Two targets crossing the 35 m x 20 m field at 10 m/s (2.4 m apart in y where they
    cross), detected with probability 0.95 (std 0.3 m), a false alarm every 4th step."""
    rng = np.random.default_rng(0)
    zs, source = [], []
    for k in range(n_steps):
        for i, (p, v) in enumerate(zip(STARTS, VELS)):
            if rng.random() < 0.95:
                zs.append(Measurement(0.25 * k, "tag", p + v * 0.25 * k + rng.normal(0, 0.3, 2)))
                source.append(i)
        if k % 4 == 1:
            zs.append(Measurement(0.25 * k, "tag", rng.uniform([0, 0], [35, 20])))
            source.append(-1)
    return zs, np.array(source)


def test_two_targets_give_two_tracks_with_ids_each_on_its_target():
    zs, source = scenario()
    tracks, state = MCMCDATracker([TAG], CONFIG).run_with_state(zs, np.random.default_rng(1))
    assert [t.id for t in tracks] == [0, 1]
    owners = set()
    for t in tracks:
        used = np.array([j for u in t.info["measurements"] for j in u])
        owner = np.bincount(source[used][source[used] >= 0]).argmax()
        owners.add(owner)
        assert np.mean(source[used] == owner) >= 0.9  # at most one report of another source
        truth = STARTS[owner] + VELS[owner] * t.times[:, None]
        assert np.mean(np.linalg.norm(t.means[:, :2] - truth, axis=1)) < 0.5
        np.testing.assert_allclose(np.diff(t.times), 0.25)  # one estimate per grid step
        assert t.covariances.shape == (len(t), 4, 4)
    assert owners == {0, 1}
    assert [tr.id for tr in state.tracks] == [0, 1] and all(tr.confirmed for tr in state.tracks)
    assert state.stats.births == 2 and state.stats.measurements == len(zs)


def test_step_by_step_with_skips_and_gaps():
    """A NaN report and an unknown sensor's report are counted skips; a missing grid point is
    an empty step; the live tracks carry ids, Gaussian beliefs and the scan's indices."""
    shifted = LinearGaussianSensor(
        "shifted", H=np.hstack([np.eye(2), np.zeros((2, 2))]), R=0.09 * np.eye(2)
    )
    shifted = _Offset(shifted)
    tr = MCMCDATracker([TAG, shifted], CONFIG, unknown_sensors="skip")
    state = tr.initial_state()
    assert isinstance(state, MCMCDATrackerState) and state.tracks == ()
    rng = np.random.default_rng(3)
    for k in [*range(6), 7, 8]:  # no scan at step 6 (t = 1.5)
        t = 0.25 * k
        a = STARTS[0] + VELS[0] * t
        scan = [
            Measurement(t, "tag", a),
            Measurement(t, "shifted", STARTS[1] + VELS[1] * t + OFFSET),
            Measurement(t, "tag", [np.nan, np.nan]),
            Measurement(t, "radar", [1.0, 2.0]),
        ]
        state = tr.step(state, t, scan, rng)
    assert state.stats.skipped_nonfinite == 8 and state.stats.skipped_unknown_sensor == 8
    assert state.stats.scans == 8 and state.association.steps == 9
    (zero, one) = state.tracks
    assert (zero.id, one.id) == (0, 1) and zero.time == 2.0
    np.testing.assert_allclose(zero.belief.mean[:2], STARTS[0] + VELS[0] * 2.0, atol=0.3)
    np.testing.assert_allclose(one.belief.mean[:2], STARTS[1] + VELS[1] * 2.0, atol=0.3)
    assert zero.measurements == (0,) and one.measurements == (1,)


class _Offset:
    """A linear position sensor with an offset ``c``: ``z = H x + c + v``."""

    def __init__(self, inner):
        self.inner = inner
        self.sensor_id, self.dim, self.angular = inner.sensor_id, inner.dim, inner.angular

    def predict(self, x):
        return self.inner.predict(x) + OFFSET

    def __getattr__(self, name):
        return getattr(self.inner, name)


def test_bad_input_is_a_clear_error_before_any_work():
    tr = MCMCDATracker([TAG], CONFIG)
    rng = np.random.default_rng(0)
    state = tr.step(tr.initial_state(), 1.0, [Measurement(1.0, "tag", [1.0, 2.0])], rng)
    with pytest.raises(MeasurementError, match=r"time=0\.5 does not come after.*time=1\.0"):
        tr.step(state, 0.5, [], rng)
    with pytest.raises(MeasurementError, match=r"time=1\.1 is invalid.*grid 1\.0 \+ k \* 0\.25"):
        tr.step(state, 1.1, [], rng)
    with pytest.raises(UnknownSensorError, match="'radar'"):
        tr.step(state, 1.25, [Measurement(1.25, "radar", [1.0, 2.0])], rng)
    with pytest.raises(ConfigError, match="rng"):
        tr.step(state, 1.25, [], None)
    with pytest.raises(ConfigError, match="position-like"):
        MCMCDATracker([RangeBearing("radar", position=[0, 0], sigma_range=1, sigma_bearing=0.1)])
    with pytest.raises(MeasurementError, match=r"time=0\.25 comes after one at time=0\.5"):
        tr.run([Measurement(0.5, "tag", [1.0, 2.0]), Measurement(0.25, "tag", [1.0, 2.0])], rng)


def test_a_tracker_without_history_forgets_what_left_the_window():
    """keep_history=False (a live node): the state keeps only the window's observations, the
    live tracks go on with their ids; whole-recording tracks are refused."""
    zs, _ = scenario(n_steps=14)
    tr = MCMCDATracker([TAG], MCMCDAConfig(n_mc=300, obs_std=0.3, window=6), keep_history=False)
    state, rng = tr.initial_state(), np.random.default_rng(1)
    times = sorted({z.time for z in zs})
    for t in times:
        state = tr.step(state, t, [z for z in zs if z.time == t], rng)
        assert len(state.association.observations) <= 6 and state.scan_index == ()
    assert [t.id for t in state.tracks] == [0, 1]
    for live in state.tracks:
        ends = [p + v * times[-1] for p, v in zip(STARTS, VELS)]
        assert min(np.linalg.norm(live.belief.mean[:2] - e) for e in ends) < 0.5
    with pytest.raises(ConfigError, match="keep_history"):
        tr.run(zs, rng)
