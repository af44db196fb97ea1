"""run_tracker: any tracker over a whole recording, scans grouped by time, empty scans at the
given times; PHDTracker.run and PMBTracker.run go through it."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Measurement, MeasurementError
from fusetrack.filters import GMPHDFilter, PhdIntensity
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix
from fusetrack.tracking import PHDTracker, PMBFilter, PMBTracker, run_tracker

TAG = PositionFix("tag", cov=np.eye(2))
STARTS = np.array([[0.0, 0.0], [50.0, 20.0]])
VEL = np.array([[2.0, 1.0], [-1.0, 0.5]])


def _birth(weight: float = 0.2) -> PhdIntensity:
    means = np.array([[x, y, 0.0, 0.0] for x, y in STARTS])  # state [x, y, vx, vy]
    covs = np.broadcast_to(np.diag([25.0, 25.0, 9.0, 9.0]), (2, 4, 4)).copy()
    return PhdIntensity(np.full(2, weight), means, covs, np.arange(2), 2)


def _recording() -> list[Measurement]:
    rng = np.random.default_rng(4)
    zs = []
    for k in range(12):
        if k == 5:
            continue  # a scan with nothing: the tracker is told by `times`
        for s, v in zip(STARTS, VEL):
            zs.append(Measurement(float(k), "tag", s + v * k + rng.normal(0, 1, 2)))
    return zs


def _phd() -> PHDTracker:
    motion = ConstantVelocity(ndim=2, q=0.5)
    phd = GMPHDFilter(motion, [TAG], _birth(), detection_probability=0.95, clutter_intensity=1e-4)
    return PHDTracker(phd)


def test_run_equals_stepping_by_hand_with_an_empty_scan_at_the_given_times():
    zs, times = _recording(), np.arange(12.0)
    tracks = _phd().run(zs, times=times)
    tracker, state = _phd(), None
    state = tracker.initial_state()
    by_id: dict[int, list[np.ndarray]] = {}
    for t in times:
        state = tracker.step(state, float(t), [m for m in zs if m.time == t])
        for tr in state.confirmed:
            by_id.setdefault(tr.id, []).append(tr.belief.mean)
    assert [t.id for t in tracks] == sorted(by_id) and len(tracks) >= 2
    for t in tracks:
        np.testing.assert_allclose(t.means, np.array(by_id[t.id]), rtol=0, atol=1e-12)
        assert t.covariances.shape == (len(t), 4, 4)
    # the empty scan at t = 5 was stepped (a missed-detection update): without it the tracks
    # after it differ
    skipped = _phd().run(zs)
    after = [t.means[t.times > 5][0] for t in tracks if np.any(t.times > 5)]
    after_skipped = [t.means[t.times > 5][0] for t in skipped if np.any(t.times > 5)]
    assert not np.allclose(np.sort(np.ravel(after)), np.sort(np.ravel(after_skipped)))
    for s, v in zip(STARTS, VEL):  # each target has a track on it at the end
        assert min(np.linalg.norm(t.means[-1, :2] - (s + v * 11)) for t in tracks) < 3.0


def test_out_of_order_is_an_error_unless_reordered():
    zs = _recording()
    shuffled = zs[::-1]
    with pytest.raises(MeasurementError, match="time"):
        _phd().run(shuffled)
    a = _phd().run(shuffled, order="reorder")
    b = _phd().run(zs)
    assert [t.id for t in a] == [t.id for t in b]
    for ta, tb in zip(a, b):
        np.testing.assert_allclose(ta.means, tb.means, atol=1e-9)


def test_pmb_tracker_runs_through_the_same_loop():
    motion = ConstantVelocity(ndim=2, q=0.5)
    pmb = PMBFilter(motion, [TAG], _birth(), detection_probability=0.95, clutter_intensity=1e-4)
    tracks = PMBTracker(pmb).run(_recording(), times=np.arange(12.0))
    assert len(tracks) == 2
    assert tracks == sorted(tracks, key=lambda t: t.id)
    generic = run_tracker(PMBTracker(pmb), _recording(), times=np.arange(12.0))
    for a, b in zip(tracks, generic):
        np.testing.assert_array_equal(a.means, b.means)


def test_cphd_filter_as_a_tracker_keeps_the_map_count_of_tracks():
    from fusetrack.filters import GMCPHDFilter

    motion = ConstantVelocity(ndim=2, q=0.5)
    cphd = GMCPHDFilter(motion, [TAG], _birth(), detection_probability=0.95, clutter_intensity=1e-4)
    tracker = PHDTracker(cphd, max_count=20)
    state = tracker.initial_state()
    assert state.intensity.map_count == 0 and state.intensity.max_count == 20
    zs = _recording()
    for t in np.arange(12.0):
        state = tracker.step(state, float(t), [m for m in zs if m.time == t])
    assert state.intensity.map_count == 2 and len(state.confirmed) == 2
    assert len({tr.id for tr in state.confirmed}) == 2
    for s, v in zip(STARTS, VEL):  # one track on each target at the end
        assert min(np.linalg.norm(tr.belief.mean[:2] - (s + v * 11)) for tr in state.confirmed) < 3
    assert len(tracker.run(zs, times=np.arange(12.0))) >= 2


def test_phd_tracker_refuses_other_filters():
    from fusetrack.core import ConfigError

    with pytest.raises(ConfigError, match="GMPHDFilter or a GMCPHDFilter"):
        PHDTracker(object())  # type: ignore[arg-type]


def test_observe_sees_every_scan_once_in_time_order_with_the_state_after_it():
    seen: list[tuple[float, float]] = []
    tracker = _phd()
    run_tracker(
        tracker,
        _recording(),
        times=np.arange(12.0),
        observe=lambda t, s: seen.append((t, float(s.intensity.expected_count))),
    )
    assert [t for t, _ in seen] == list(np.arange(12.0))  # the empty scan at t = 5 too
    state = tracker.initial_state()
    for t in range(12):
        state = tracker.step(state, float(t), [m for m in _recording() if m.time == t])
        assert seen[t][1] == pytest.approx(float(state.intensity.expected_count), abs=1e-12)
