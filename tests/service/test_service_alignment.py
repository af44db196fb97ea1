"""Ring buffers and tick alignment against hand-worked cases; the engine against run_filter."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Measurement
from fusetrack.filters import run_filter
from fusetrack.service.alignment import Aligner, Reading, SensorBuffer
from fusetrack.service.engine import FusionEngine, build_filter
from fusetrack.service.replay import demo_scenario


def r(i, sensor, t, v=0.0):
    return Reading(i, sensor, t, np.array([v]))


def test_ring_buffer_keeps_time_order_and_drops_the_oldest():
    b = SensorBuffer(size=3)
    for i, t in enumerate([2.0, 1.0, 3.0, 0.5]):
        b.push(r(i, "a", t))
    # 0.5 arrived last but is the oldest: it is the one dropped when the 4th came
    assert [x.time for x in b.items] == [1.0, 2.0, 3.0] and b.dropped == 1
    assert [x.time for x in b.take_until(2.0)] == [1.0, 2.0]
    assert [x.time for x in b.items] == [3.0]


def test_all_alignment_hand_case():
    # 2 Hz from 0: tick 1 at 0.5 owns (0, 0.5], tick 2 at 1.0 owns (0.5, 1.0]
    al = Aligner(["a", "b"], rate_hz=2.0, start=0.0, alignment="all", lag=0.25)
    for x in [r(1, "b", 0.5), r(2, "a", 0.5), r(3, "a", 0.2), r(4, "b", 0.7), r(5, "a", 1.0)]:
        al.push(x)
    assert al.due(0.74) == []  # 0.5 + lag 0.25 not yet reached
    assert al.due(1.3) == [1, 2]  # 1.0 + 0.25 <= 1.3
    # tick 1: time order, ties in config sensor order (a before b) whatever the arrival
    assert [x.id for x in al.take(1)] == [3, 2, 1]
    assert [x.id for x in al.take(2)] == [4, 5]
    assert al.is_late(1.0) and not al.is_late(1.01)
    with pytest.raises(ValueError, match="tick"):
        al.take(4)  # tick 3 comes first


def test_closest_alignment_hand_case():
    # 1 Hz; tick 1 at t=1 owns (0, 1.5] (half a period past it), tick 2 at t=2 owns (1.5, 2.5]
    al = Aligner(["a", "b"], rate_hz=1.0, start=0.0, alignment="closest", lag=0.0)
    for x in [r(1, "a", 0.6), r(2, "a", 1.3), r(3, "a", 0.9), r(4, "b", 1.5), r(5, "b", 1.6)]:
        al.push(x)
    assert al.due(1.49) == [] and al.due(1.5) == [1]
    got = al.take(1)
    # a: |0.9-1| = 0.1 beats 1.3 (0.3) and 0.6 (0.4); b: 1.5 (in this window), 1.6 waits
    assert sorted(x.id for x in got) == [3, 4]
    assert al.superseded == 2
    assert [x.id for x in al.take(2)] == [5]
    assert al.fused_until == 2.5


def _truth_run(network, seed=2, duration=15.0):
    scn = demo_scenario(network, seed=seed, duration=duration)
    readings = [Reading(i, x.sensor, x.time, np.array(x.value)) for i, x in enumerate(scn.readings)]
    return scn, readings


@pytest.mark.parametrize("kind", ["ekf", "ukf", "pf"])
def test_engine_equals_offline_run_filter(network, kind):
    """Tick-by-tick fusion gives exactly the offline filter's estimates at the tick times."""
    cfg = network.model_copy(
        update={"tracker": network.tracker.model_copy(update={"filter": kind, "particles": 300})}
    )
    scn, readings = _truth_run(cfg)
    al = Aligner([s.id for s in cfg.sensors], cfg.fusion.rate_hz, 0.0, "all")
    for x in readings:
        al.push(x)
    engine = FusionEngine(cfg, 0.0)
    states = [engine.step(k, al.tick_time(k), al.take(k)) for k in al.due(15.0)]
    ticks = np.array([s.time for s in states])
    ms = [Measurement(x.time, x.sensor, x.value) for x in readings]
    filt = build_filter(cfg)
    track = run_filter(
        filt,
        cfg.tracker.prior(),
        ms,
        rng=np.random.default_rng(cfg.tracker.seed),
        times=ticks,
        t0=0.0,
    )
    keep = np.isin(np.round(track.times, 9), np.round(ticks, 9))
    np.testing.assert_allclose([s.state for s in states], track.means[keep], rtol=0, atol=1e-9)
    np.testing.assert_allclose([s.covariance for s in states], track.covariances[keep], atol=1e-9)
    err = np.linalg.norm(np.array([s.position for s in states]) - scn.truth[1:31, :2], axis=1)
    assert np.sqrt(np.mean(err**2)) < 3.0  # predict-only is 10-30 m on these runs


def test_closest_alignment_fuses_one_reading_per_sensor_at_the_tick(network):
    cfg = network.model_copy(
        update={
            "fusion": network.fusion.model_copy(update={"alignment": "closest", "rate_hz": 1.0})
        }
    )
    _, readings = _truth_run(cfg, duration=6.0)
    al = Aligner([s.id for s in cfg.sensors], 1.0, 0.0, "closest")
    for x in readings:
        al.push(x)
    engine = FusionEngine(cfg, 0.0)
    used = []
    for k in al.due(6.0):
        chosen = al.take(k)
        assert len({x.sensor for x in chosen}) == len(chosen)  # at most one per sensor
        used.append(chosen)
        engine.step(k, al.tick_time(k), chosen)
    # offline: the same chosen readings, stamped at their tick
    ms = [Measurement(float(k + 1), x.sensor, x.value) for k, ch in enumerate(used) for x in ch]
    track = run_filter(
        build_filter(cfg), cfg.tracker.prior(), ms, times=np.arange(1.0, len(used) + 1), t0=0.0
    )
    np.testing.assert_allclose(engine.belief.mean, track.means[-1], atol=1e-9)
