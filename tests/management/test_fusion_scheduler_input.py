"""The fusion node's intake: closest-timestamp selection and every kind of bad packet counted."""

import numpy as np

from fusetrack.management.fusion_scheduler import FusionScheduler, Packet


def packet(sid, seq, t, n=36, value=1.0):
    return Packet(sid, seq, t, np.full(n, value))


def test_takes_the_closest_reading_per_sensor():
    s = FusionScheduler({"A1": 36, "V1": 160})
    for k, t in enumerate([0.0, 0.26, 0.49, 0.77]):
        s.receive(packet("A1", k, t, value=k))
    s.receive(packet("V1", 0, 0.40, n=160))
    got = s.take(0.5)
    assert got["A1"].seq == 2 and got["V1"].seq == 0
    assert s.take(2.0) == {} and s.stats.missing_at_tick == 2


def test_bad_packets_are_counted_and_skipped():
    s = FusionScheduler({"A1": 36})
    assert s.receive(packet("A1", 0, 1.0))
    assert not s.receive(packet("A1", 0, 1.0))  # duplicate
    assert not s.receive(packet("A9", 0, 1.0))  # unknown sensor
    assert not s.receive(packet("A1", 1, 1.25, n=35))  # wrong length
    assert not s.receive(packet("A1", 2, 1.5, value=np.nan))  # non-finite
    s.take(10.0)
    assert not s.receive(packet("A1", 3, 1.75))  # far too late for any future tick
    st = s.stats
    assert (st.duplicate, st.unknown_sensor, st.wrong_length, st.non_finite, st.late) == (
        1,
        1,
        1,
        1,
        1,
    )
    assert st.received == 6 and st.accepted == 1


def test_clock_jump_is_detected_and_the_sensor_recovers():
    s = FusionScheduler({"A1": 36}, period=0.25)
    for k in range(4):
        s.receive(packet("A1", k, 0.25 * k))
    assert s.receive(packet("A1", 4, 0.25 * 4 + 30.0))  # the node's clock jumped by 30 s
    assert s.stats.clock_jump == 1
    assert s.receive(packet("A1", 5, 0.25 * 5 + 30.0))  # consistent again: no new jump
    assert s.stats.clock_jump == 1
    assert s.take(31.25)["A1"].seq == 5


def test_random_garbage_never_crashes():
    rng = np.random.default_rng(0)
    s = FusionScheduler({"A1": 36, "V1": 160}, capacity=4)
    for k in range(300):
        sid = ["A1", "V1", "X"][int(rng.integers(3))]
        n = int(rng.choice([36, 160, 5]))
        vals = rng.normal(size=n)
        if rng.random() < 0.1:
            vals[0] = np.inf
        s.receive(Packet(sid, int(rng.integers(20)), float(rng.normal(k * 0.1, 3.0)), vals))
        if k % 10 == 0:
            s.take(k * 0.1)
    assert s.stats.received == 300
    assert sum(len(b) for b in s._buffers.values()) <= 8
