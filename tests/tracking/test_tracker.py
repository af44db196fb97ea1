"""The multi-target tracker end to end: two targets in clutter, deletion, M-of-N confirmation,
exact agreement with the single-target filter, two sensor kinds in one scan, bad input.

The associator here is :class:`~fusetrack.association.GlobalNearestNeighbour`; JPDA and the
other associators are compared on a hand-worked crossing in ``test_associators.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from _tracking_scenarios import MOTION, POS, SIGMA, WIDE, scenario, tracker

from fusetrack.association import Association, GlobalNearestNeighbour, SingleHypothesis
from fusetrack.core import (
    ConfigError,
    Measurement,
    MeasurementError,
    UnknownSensorError,
)
from fusetrack.filters import ExtendedKalmanFilter, KalmanFilter, run_filter
from fusetrack.sensors import PositionFix, RangeBearing
from fusetrack.tracking import (
    AnyOf,
    ExistenceDeleter,
    InverseMeasurementPrior,
    MissedCountDeleter,
    MofNInitiator,
    MultiTargetTracker,
    SinglePointInitiator,
)


@pytest.mark.parametrize("seed", [0, 3, 7])
def test_two_targets_in_clutter_give_two_tracks_with_persistent_ids(seed):
    """Exactly two confirmed tracks, each fed by one target only, none from clutter.

    Why no clutter track: a false alarm starts a tentative track whose first gate (velocity
    std 3 m/s over 1 s, S ~ 9.3 m^2 per axis, P_G = 0.999: d^2 <= 13.8) covers ~400 m^2, i.e.
    0.02 false alarms; after such a hit the two-point velocity shrinks the gate to ~75 m^2
    (0.004 false alarms). Confirmation needs 3 of 4 scans, so about 3 * 0.02 * 2 * 0.004 ~ 5e-4
    per false alarm: 0.04 false tracks over the 80 false alarms of a run.
    """
    zs, _, source = scenario(seed=seed)
    tracks = tracker().run(zs, np.random.default_rng(0))
    assert len(tracks) == 2
    assert len({t.id for t in tracks}) == 2
    owners = set()
    for t in tracks:
        used = np.concatenate([np.array(u, dtype=int) for u in t.info["measurements"]])
        owner = np.bincount(source[used][source[used] >= 0]).argmax()
        owners.add(owner)
        assert np.all(source[used] == owner)  # never a clutter point, never the other target
        assert t.info["deleted"] is None and t.times[-1] == 39 and t.times[0] <= 2
        confirmed = t.info["confirmed"]
        assert confirmed[-1] and np.median(t.info["existence"][confirmed]) > 0.99
        assert np.all(np.diff(t.times) == 1.0)  # one estimate per scan, no gap
    assert owners == {0, 1}


def test_position_rmse_matches_the_filter_covariance():
    """Position RMSE (from the 5th scan on, past the initiation transient) is at most 1.5
    times the filter's own position std sqrt(mean tr P_pos): the truth follows the filter's
    motion model, so a correct tracker is consistent (ratio 1; over seeds 0-9 the ratio is
    0.85-1.16, and 1.66 for one track hit by a 3.5-sigma measurement). The filter's own std
    lies between the steady-state posterior 0.55 m (P_D = 1, Riccati solution) and the
    prediction-only 0.89 m: below 0.75 m with P_D = 0.9; a tracker that kept predictions or
    lost its measurements would fail both."""
    zs, truth, source = scenario(seed=3)
    tracks = tracker().run(zs, np.random.default_rng(0))
    for t in tracks:
        used = np.concatenate([np.array(u, dtype=int) for u in t.info["measurements"]])
        target = np.bincount(source[used][source[used] >= 0]).argmax()
        keep = t.times >= 5
        err = t.means[keep, :2] - truth[target, t.times[keep].astype(int), :2]
        rmse = np.sqrt(np.mean(np.sum(err**2, axis=1)))
        own = np.sqrt(np.mean(np.trace(t.covariances[keep, :2, :2], axis1=1, axis2=2)))
        assert rmse < 1.5 * own
        assert 0.55 < own < 0.75


def test_a_target_that_disappears_is_deleted_at_its_max_misses_th_missed_scan():
    zs, _, _ = scenario(seed=5, p_detect=1.0, last_scan=(None, 15))
    tracks = tracker(deleter=MissedCountDeleter(3)).run(zs, np.random.default_rng(0))
    assert len(tracks) == 2
    gone = next(t for t in tracks if t.info["deleted"] is not None)
    assert gone.info["deleted"] == 18.0  # misses at scans 16, 17, 18: deleted in scan 18
    assert gone.times[-1] == 17.0
    assert [len(u) for u in gone.info["measurements"][-2:]] == [0, 0]
    existence = gone.info["existence"]
    assert np.all(np.diff(existence[-3:]) < 0)  # each missed scan lowers it (IPDA)
    other = next(t for t in tracks if t is not gone)
    assert other.info["deleted"] is None and other.times[-1] == 39


def test_existence_deleter_follows_the_ipda_recursion_over_missed_scans():
    """After the target vanishes (scan 15) each scan predicts the existence with P_S = 0.99
    and updates it for a miss, r <- (1 - P_D P_G) r / (1 - P_D P_G r): ~1 -> 0.909 -> 0.476
    -> 0.082 (P_D P_G = 0.9 * 0.999), so with threshold 0.2 the track ends in the third missed scan."""
    zs, _, _ = scenario(seed=5, p_detect=1.0, last_scan=(None, 15), clutter=0.0)
    deleter = AnyOf(MissedCountDeleter(100), ExistenceDeleter(0.2))
    tracks = tracker(deleter=deleter, p_detect=0.9).run(zs, np.random.default_rng(0))
    gone = next(t for t in tracks if t.info["deleted"] is not None)
    k = int(np.flatnonzero(gone.times == 15.0)[0])
    r, expected = gone.info["existence"][k], []
    for _ in range(3):
        r = 0.99 * r
        r = (1 - 0.9 * 0.999) * r / (1 - 0.9 * 0.999 * r)
        expected.append(r)
    np.testing.assert_allclose(gone.info["existence"][k + 1 :], expected[:2], rtol=1e-12)
    assert expected[2] < 0.2 <= expected[1]
    assert gone.info["deleted"] == 18.0 and gone.times[-1] == 17.0


def _scan(tr, state, t, hit):
    zs = [Measurement(t, "pos", [1.0 * t, 0.0])] if hit else []
    return tr.step(state, t, zs)


@pytest.mark.parametrize(
    ("m", "n", "hits", "expected"),
    [
        # birth, miss, hit: 2 of 3 reached at the third scan, not before
        (2, 3, [1, 0, 1], ["tentative", "tentative", "confirmed"]),
        # birth, miss, miss: 2 of 3 can no longer happen at the third scan
        (2, 3, [1, 0, 0], ["tentative", "tentative", "dropped"]),
        # birth, miss: 1 + 1 scan left < 3
        (3, 3, [1, 0], ["tentative", "dropped"]),
        (3, 3, [1, 1, 1], ["tentative", "tentative", "confirmed"]),
        (3, 5, [1, 0, 1, 0, 1], ["tentative"] * 4 + ["confirmed"]),
        (1, 1, [1], ["confirmed"]),
    ],
)
def test_m_of_n_confirms_at_the_m_th_hit_and_not_before(m, n, hits, expected):
    tr = tracker(initiator=MofNInitiator(m, n, InverseMeasurementPrior([POS], WIDE)))
    state = tr.initial_state()
    seen = []
    for t, hit in enumerate(hits):
        state = _scan(tr, state, float(t), hit)
        if not state.tracks:
            seen.append("dropped")
        else:
            (track,) = state.tracks
            assert track.id == 0 and track.scans == t + 1 and track.hits == sum(hits[: t + 1])
            seen.append("confirmed" if track.confirmed else "tentative")
    assert seen == expected


def test_one_target_without_clutter_equals_run_filter():
    """P_D = 1, no clutter, irregular scan times: the tracker's track is the Kalman filter's."""
    rng = np.random.default_rng(11)
    times = np.cumsum(np.r_[0.0, rng.uniform(0.3, 1.7, 24)])
    x = np.array([3.0, -2.0, 1.0, 0.5])
    zs = []
    for k, t in enumerate(times):
        if k:
            x = MOTION.sample(x, t - times[k - 1], rng)
        zs.append(Measurement(t, "pos", x[:2] + SIGMA * rng.standard_normal(2)))
    kf = KalmanFilter(MOTION, [POS])
    prior_from = InverseMeasurementPrior([POS], WIDE)
    tr = tracker(initiator=SinglePointInitiator(prior_from), p_detect=1.0, filt=kf)
    (track,) = tr.run(zs, rng)
    ref = run_filter(kf, prior_from(zs[0]), zs[1:], t0=times[0])
    assert track.id == 0 and np.array_equal(track.times, times)
    np.testing.assert_allclose(track.means[0], prior_from(zs[0]).mean, rtol=0, atol=1e-12)
    np.testing.assert_allclose(track.means[1:], ref.means, rtol=0, atol=1e-12)
    np.testing.assert_allclose(track.covariances[1:], ref.covariances, rtol=0, atol=1e-12)
    assert track.info["measurements"] == tuple((k,) for k in range(len(times)))


def test_two_sensor_kinds_in_one_scan_are_both_used():
    """A position fix and a range-bearing radar report both targets every scan: each track
    uses one report of each sensor per scan, its own, and equals the EKF run on them."""
    tag = PositionFix("tag", cov=0.25 * np.eye(2))
    radar = RangeBearing("radar", position=[0.0, 0.0], sigma_range=0.5, sigma_bearing=0.005)
    ekf = ExtendedKalmanFilter(MOTION, [tag, radar])
    rng = np.random.default_rng(2)
    x = np.array([[60.0, 10.0, 1.0, 1.0], [10.0, 80.0, 1.5, -0.5]])
    zs, source = [], []
    for k in range(15):
        if k:
            x = MOTION.sample(x, 1.0, rng)
        for i in (1, 0):
            zs.append(Measurement(k, "tag", tag.simulate(x[i], rng)))
            source.append((i, "tag"))
        for i in (0, 1):
            zs.append(Measurement(k, "radar", radar.simulate(x[i], rng)))
            source.append((i, "radar"))
    prior_from = InverseMeasurementPrior([tag], WIDE)  # only the tag starts tracks
    tr = MultiTargetTracker(
        ekf,
        [tag, radar],
        GlobalNearestNeighbour(),
        SinglePointInitiator(prior_from),
        MissedCountDeleter(3),
        p_detect=1.0,
        clutter_density={"tag": 1e-4, "radar": 1e-2},
    )
    tracks = tr.run(zs, rng)
    assert len(tracks) == 2
    for t in tracks:
        used = t.info["measurements"]
        assert all(len(u) == 2 for u in used)
        owner = source[used[0][0]][0]
        assert all(sorted(source[j][1] for j in u) == ["radar", "tag"] for u in used)
        assert all(source[j][0] == owner for u in used for j in u)
        # the same EKF on the track's own reports (tag then radar at each time)
        first_tag, first_radar = used[0][0], used[0][1]
        own = [zs[j] for u in used[1:] for j in u]
        ref = run_filter(ekf, prior_from(zs[first_tag]), [zs[first_radar], *own], t0=0.0)
        np.testing.assert_allclose(t.means, ref.means, rtol=0, atol=1e-9)


class CountingKF(KalmanFilter):
    calls = 0

    def predict(self, *a, **k):
        CountingKF.calls += 1
        return super().predict(*a, **k)

    def update_with_likelihood(self, *a, **k):
        CountingKF.calls += 1
        return super().update_with_likelihood(*a, **k)


def test_bad_configuration_fails_before_any_work():
    prior_from = InverseMeasurementPrior([POS], WIDE)
    with pytest.raises(ConfigError, match=r"m=3 is invalid.*at most n=2"):
        MofNInitiator(3, 2, prior_from)
    with pytest.raises(ConfigError, match="m=0"):
        MofNInitiator(0, 2, prior_from)
    for bad in (0.0, 1.5, -0.1):
        with pytest.raises(ConfigError, match=rf"p_detect={bad}"):
            tracker(p_detect=bad)
    with pytest.raises(ConfigError, match=r"p_detect\['pos'\]"):
        tracker(p_detect={"pos": 0.0})
    with pytest.raises(ConfigError, match="clutter_density"):
        MultiTargetTracker(
            KalmanFilter(MOTION, [POS]),
            [POS],
            GlobalNearestNeighbour(),
            MofNInitiator(1, 1, prior_from),
            MissedCountDeleter(1),
            0.9,
            0.0,
        )
    with pytest.raises(ConfigError, match="gate_probability"):
        tracker(gate_probability=0.0)
    with pytest.raises(ConfigError, match="associator"):
        MultiTargetTracker(
            KalmanFilter(MOTION, [POS]),
            [POS],
            object(),
            MofNInitiator(1, 1, prior_from),
            MissedCountDeleter(1),
            0.9,
            1e-4,
        )
    with pytest.raises(ConfigError, match="sensors"):  # a sensor the filter does not know
        MultiTargetTracker(
            KalmanFilter(MOTION, [POS]),
            [POS, PositionFix("tag", cov=np.eye(2))],
            GlobalNearestNeighbour(),
            MofNInitiator(1, 1, prior_from),
            MissedCountDeleter(1),
            0.9,
            1e-4,
        )
    with pytest.raises(ConfigError, match=r"sensors='radar'"):  # cannot invert a radar
        InverseMeasurementPrior(
            [RangeBearing("radar", position=[0.0, 0.0], sigma_range=1.0, sigma_bearing=0.1)], WIDE
        )


def test_unknown_sensor_or_time_going_back_fails_before_any_filter_call():
    zs, _, _ = scenario(seed=1, n_scans=5)
    CountingKF.calls = 0
    tr = tracker(filt=CountingKF(MOTION, [POS]))
    with pytest.raises(UnknownSensorError, match=r"sensor_id='radar'.*\['pos'\]"):
        tr.run([*zs, Measurement(4.0, "radar", [1.0, 2.0])], np.random.default_rng(0))
    assert CountingKF.calls == 0
    with pytest.raises(MeasurementError, match=r"value\.shape"):
        tr.run([*zs, Measurement(4.0, "pos", [1.0, 2.0, 3.0])], np.random.default_rng(0))
    assert CountingKF.calls == 0
    with pytest.raises(MeasurementError, match=r"one report"):
        tr.run([*zs, Measurement(4.0, "pos", np.zeros((3, 2)))], np.random.default_rng(0))
    assert CountingKF.calls == 0
    state = tr.step(tr.initial_state(), 3.0, [zs[0]])
    with pytest.raises(MeasurementError, match=r"time=2\.0"):
        tr.step(state, 2.0, [])


def test_the_module_examples_run():
    import doctest

    from fusetrack.tracking import initiators, tracker

    for module in (tracker, initiators):
        result = doctest.testmod(module)
        assert result.failed == 0 and result.attempted > 0


class Soft:
    """A JPDA-like stand-in: every track takes each gated measurement with a probability
    proportional to its likelihood ratio, and is missed with weight exp(log_missed)."""

    def associate(self, scores, rng=None):
        ratios = np.exp(scores.log_likelihood - scores.log_clutter)
        hyp = {}
        for k, i in enumerate(scores.track_ids):
            w = np.r_[np.exp(scores.log_missed[k]), ratios[k]]
            w = w / w.sum()
            hyp[i] = tuple(
                SingleHypothesis(i, None if j == 0 else j - 1, float(p))
                for j, p in enumerate(w)
                if p > 0
            )
        return Association(hyp, ())


def test_a_soft_associator_gives_the_pda_combination_and_the_ipda_existence():
    from fusetrack.tracking import combine_hypotheses, update_existence

    prior_from = InverseMeasurementPrior([POS], WIDE)
    tr = MultiTargetTracker(
        KalmanFilter(MOTION, [POS]),
        [POS],
        Soft(),
        SinglePointInitiator(prior_from),
        MissedCountDeleter(3),
        p_detect=0.9,
        clutter_density=0.01,
        gate_probability=0.999,
    )
    state = tr.step(tr.initial_state(), 0.0, [Measurement(0.0, "pos", [0.0, 0.0])])
    zs = [Measurement(1.0, "pos", v) for v in ([0.3, -0.2], [-0.8, 0.9], [40.0, 40.0])]
    after = tr.step(state, 1.0, zs)
    track, newborn = after.tracks
    assert newborn.measurements == (2,)  # in no gate: never offered to the associator
    pred = tr.filter.predict(state.tracks[0].belief, 1.0)
    posts, lls = zip(*(tr.filter.update_with_likelihood(pred, [z]) for z in zs[:2]))
    ratios = 0.9 * np.exp(np.array(lls, dtype=float)) / 0.01
    w = np.r_[1 - 0.9 * 0.999, ratios]
    expected = combine_hypotheses([pred, *posts], w / w.sum())
    np.testing.assert_allclose(track.belief.mean, expected.mean, rtol=1e-12)
    np.testing.assert_allclose(track.belief.cov, expected.cov, rtol=1e-12)
    assert track.measurements == (0, 1)  # the far one is outside the gate
    np.testing.assert_allclose(track.probabilities, w[1:] / w.sum(), rtol=1e-12)
    r = update_existence(0.99 * 0.5, 0.9 * 0.999, np.log(ratios))
    assert track.existence == pytest.approx(r, rel=1e-12)
    assert track.hits == 2 and track.misses == 0


def test_a_particle_filter_tracks_too():
    """Births become particles (``filter.initialize``); each track keeps its most probable
    hypothesis' posterior. One target, no clutter: the track follows it."""
    from fusetrack.filters import BootstrapFilter

    zs, truth, source = scenario(seed=4, n_scans=12, p_detect=1.0, clutter=0.0)
    pf = BootstrapFilter(MOTION, [POS], n_particles=2000, engine="numpy")
    tr = tracker(filt=pf, initiator=SinglePointInitiator(InverseMeasurementPrior([POS], WIDE)))
    tracks = tr.run(zs, np.random.default_rng(0))
    assert len(tracks) == 2
    for t in tracks:
        (owner,) = {int(source[j]) for u in t.info["measurements"] for j in u}
        err = t.means[:, :2] - truth[owner, :, :2]
        assert np.sqrt(np.mean(np.sum(err**2, axis=1))) < 0.9  # 2-D measurement RMSE: 0.71


def test_only_the_sensors_that_scanned_count_a_miss():
    tag = PositionFix("tag", cov=0.25 * np.eye(2))
    kf = KalmanFilter(MOTION, [POS, tag])
    tr = MultiTargetTracker(
        kf,
        [POS, tag],
        GlobalNearestNeighbour(),
        SinglePointInitiator(InverseMeasurementPrior([POS], WIDE)),
        MissedCountDeleter(2),
        p_detect=0.9,
        clutter_density=1e-4,
    )
    state = tr.step(tr.initial_state(), 0.0, [Measurement(0.0, "pos", [0.0, 0.0])])
    quiet = tr.step(state, 1.0, [], scanned=["tag"])  # the tag looked, saw nothing: one miss
    assert quiet.tracks[0].misses == 1 and quiet.tracks[0].scans == 2
    assert tr.step(quiet, 2.0, [], scanned=["tag"]).tracks == ()  # second miss: deleted
    with pytest.raises(UnknownSensorError, match="scanned"):
        tr.step(state, 1.0, [], scanned=["radar"])


def test_the_batched_kalman_path_gives_the_tracks_of_one_call_per_track():
    zs, _, _ = scenario(seed=3, n_scans=20)
    fast = tracker().run(zs, np.random.default_rng(0))
    slow = tracker(filt=CountingKF(MOTION, [POS])).run(zs, np.random.default_rng(0))
    assert [t.id for t in fast] == [t.id for t in slow]
    for a, b in zip(fast, slow):
        assert a.info["measurements"] == b.info["measurements"]
        np.testing.assert_allclose(a.means, b.means, rtol=0, atol=1e-9)
        np.testing.assert_allclose(a.covariances, b.covariances, rtol=0, atol=1e-9)
