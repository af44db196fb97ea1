"""Bad input (issue 17): empty scans, a scan of 5000 false alarms, unknown sensors, NaN
reports, out-of-order scans. Each is a clear error or a counted skip, never a crash or a
silently lost track."""

from __future__ import annotations

import numpy as np
import pytest
from _tracking_scenarios import CLUTTER_RATE, MOTION, POS, SIDE, WIDE, tracker, with_flood

from fusetrack.association import JointProbabilisticDataAssociation, TrackOrientedMHT
from fusetrack.core import Measurement, MeasurementError, UnknownSensorError
from fusetrack.filters import GMPHDFilter, KalmanFilter, PhdIntensity
from fusetrack.tracking import (
    InverseMeasurementPrior,
    MHTTracker,
    MissedCountDeleter,
    MultiTargetTracker,
    PHDInitiator,
    SinglePointInitiator,
)

PRIOR = InverseMeasurementPrior([POS], WIDE)


def _one_track(kind=MultiTargetTracker, associator=None, **kw):
    tr = kind(
        KalmanFilter(MOTION, [POS]), [POS],
        associator or JointProbabilisticDataAssociation(),
        SinglePointInitiator(PRIOR), MissedCountDeleter(2),
        p_detect=0.9, clutter_density=1e-4, **kw,
    )  # fmt: skip
    return tr, tr.step(tr.initial_state(), 0.0, [Measurement(0.0, "pos", [0.0, 0.0])])


@pytest.mark.parametrize("kind", ["tracker", "mht"])
def test_empty_scans_are_misses_and_counted(kind):
    cls, assoc = (MHTTracker, TrackOrientedMHT()) if kind == "mht" else (MultiTargetTracker, None)
    tr, state = _one_track(cls, assoc)
    nothing = tr.step(tr.initial_state(), 0.0, [])
    assert nothing.tracks == () and nothing.stats.empty_scans == 1
    once = tr.step(state, 1.0, [])
    assert once.tracks[0].misses == 1 and once.stats.empty_scans == 1
    assert tr.step(once, 2.0, []).tracks == ()  # the second miss deletes it (max_misses = 2)
    assert tr.step(once, 2.0, []).stats.deleted == 1


@pytest.mark.parametrize("kind", ["tracker", "mht"])
def test_nan_reports_are_counted_skips_never_a_miss_or_a_loss(kind):
    cls, assoc = (MHTTracker, TrackOrientedMHT()) if kind == "mht" else (MultiTargetTracker, None)
    tr, state = _one_track(cls, assoc)
    nan = Measurement(1.0, "pos", [np.nan, 1.0])
    bad_cov = Measurement(1.0, "pos", [0.1, 0.0], covariance=[[np.nan, 0.0], [0.0, 1.0]])
    for _ in range(3):  # three scans of corrupt reports only: the sensor did not look
        state = tr.step(state, state.time + 1.0, [nan, bad_cov])
    (track,) = state.tracks
    assert track.misses == 0 and track.scans == 1 and track.time == 3.0  # predicted, not missed
    assert state.stats.skipped_nonfinite == 6 and state.stats.empty_scans == 3
    # a NaN next to a good report: the good one is used, the NaN skipped
    state = tr.step(state, 4.0, [nan, Measurement(4.0, "pos", [0.0, 0.0])])
    assert state.tracks[0].hits == 2 and state.tracks[0].measurements == (1,)
    assert state.stats.skipped_nonfinite == 7 and len(state.tracks) == 1
    # in a recording: the corrupt scan is in the track, predicted, using nothing
    zs = [Measurement(0.0, "pos", [0.0, 0.0]), Measurement(1.0, "pos", [np.nan, 0.0])]
    (whole,) = tr.run([*zs, Measurement(2.0, "pos", [0.0, 0.0])])
    assert whole.info["measurements"] == ((0,), (), (2,))


def test_unknown_sensors_raise_by_default_or_are_counted_skips():
    radar = Measurement(1.0, "radar", [1.0, 2.0])
    tr, state = _one_track()
    with pytest.raises(UnknownSensorError, match=r"sensor_id='radar'.*\['pos'\]"):
        tr.step(state, 1.0, [radar])
    tr, state = _one_track(unknown_sensors="skip")
    state = tr.step(state, 1.0, [radar, Measurement(1.0, "pos", [0.1, 0.0])])
    assert state.stats.skipped_unknown_sensor == 1 and state.tracks[0].hits == 2
    tracks, final = tr.run_with_state([Measurement(0.0, "pos", [0.0, 0.0]), radar])
    assert final.stats.skipped_unknown_sensor == 1 and len(tracks) == 1


def test_out_of_order_scans_name_the_times():
    tr, state = _one_track()
    with pytest.raises(MeasurementError, match=r"scan time=-1\.0 comes before .*time=0\.0"):
        tr.step(state, -1.0, [])
    zs = [Measurement(1.0, "pos", [0.0, 0.0]), Measurement(0.5, "pos", [0.0, 0.0])]
    with pytest.raises(MeasurementError, match=r"time=0\.5 comes after one at time=1\.0"):
        tr.run(zs)
    assert len(tr.run(zs, order="reorder")) == 1


def test_a_scan_of_5000_false_alarms_starts_no_confirmed_track():
    """M-of-N: every false alarm starts a tentative track and each is dropped by the third
    scan after (3 of 4 impossible); the gate keeps the associator's problem to the few false
    alarms near each track."""
    zs = with_flood()
    tracks, state = tracker().run_with_state(zs, np.random.default_rng(0), order="reorder")
    assert len(tracks) == 2 and all(t.times[-1] == 9 for t in tracks)
    assert state.stats.births >= 5000 and state.stats.dropped >= 5000 - 10
    assert state.stats.confirmed == 2 and len(state.confirmed) == 2


def test_the_phd_initiator_starts_nothing_from_5000_false_alarms():
    birth = PhdIntensity([0.05], [[100.0, 100.0, 0.0, 0.0]], [np.diag([1e4, 1e4, 9.0, 9.0])])
    phd = GMPHDFilter(
        MOTION, [POS], birth, detection_probability=0.9,
        clutter_intensity=CLUTTER_RATE / SIDE**2, merge_threshold=0.0,
    )  # fmt: skip
    zs = with_flood()
    tr = tracker(initiator=PHDInitiator(phd, m=2, n=3))
    tracks, state = tr.run_with_state(zs, np.random.default_rng(0), order="reorder")
    assert len(tracks) == 2 and state.stats.births == 2
    assert state.initiator_state.saturated == 1  # the flood scan: counted, started nothing
