"""The fusion node survives bad input: dropped, duplicated, late and malformed packets, a node
whose clock jumps, a silent node — all counted, and the track goes on (Kushwaha 2010 pipeline)."""

import numpy as np

from fusetrack.experiments.kushwaha2010.scene import (
    VIDEO_ANGLES,
    Recording,
    VehiclePass,
    all_likelihoods,
    default_layout,
    fusion_input,
    run_sbe,
)
from fusetrack.management.fusion_scheduler import Packet
from fusetrack.perception.audio_beamforming import beam_angles


def synthetic_packets(layout, vehicle, times, rng):
    """Clean detection functions pointing at the vehicle (no sound or pixels: fast)."""
    packets = []
    for seq, t in enumerate(times):
        xy = vehicle.centre(t)
        for sid, x, y, h in layout.audio:
            d = np.angle(np.exp(1j * (beam_angles() - (np.arctan2(xy[1] - y, xy[0] - x) - h))))
            lam = 1.0 + np.exp(-0.5 * (d / 0.4) ** 2)
            packets.append(Packet(sid, seq, t, lam, t + 0.03))
        for sid, x, y, h in layout.video:
            b = np.angle(np.exp(1j * (np.arctan2(xy[1] - y, xy[0] - x) - h)))
            lam = 200.0 * np.exp(-0.5 * ((VIDEO_ANGLES - b) / 0.02) ** 2)
            packets.append(Packet(sid, seq, t + rng.uniform(-0.01, 0.01), lam, t + 0.02))
    return packets


def test_fusion_node_counts_bad_packets_and_keeps_tracking():
    rng = np.random.default_rng(0)
    layout = default_layout()
    vehicle = VehiclePass(x0=0.0, lane_y=8.5, speed=10.0)
    times = np.arange(0.0, 3.25, 0.25)
    good = synthetic_packets(layout, vehicle, times, rng)
    bad = []
    for p in good[::7]:
        bad.append(p)  # duplicate
    bad.append(Packet("A2", 99, 1.0, np.ones(35), 1.05))  # wrong length
    bad.append(Packet("V1", 98, 1.0, np.full(160, np.nan), 1.05))  # non-finite
    bad.append(Packet("ghost", 0, 1.0, np.ones(36), 1.05))  # unknown sensor
    jumped = [
        Packet(
            p.sensor_id,
            p.seq,
            p.timestamp + (40.0 if p.timestamp >= 1.5 else 0.0),
            p.values,
            p.arrival,
        )
        for p in good
        if p.sensor_id == "A3"
    ]
    silent = [p for p in good if p.sensor_id != "A6"]  # node A6 never reports
    packets = [p for p in silent if p.sensor_id != "A3"] + jumped + bad
    packets.sort(key=lambda p: p.arrival)
    rec = Recording(packets, [vehicle], 0.0, 3.0, np.zeros(len(packets)), audio_threshold=0.0)
    fin = fusion_input(rec, rng, packet_loss=0.0)
    st = fin.stats
    assert (
        st.duplicate > 0 and st.wrong_length == 1 and st.non_finite == 1 and st.unknown_sensor == 1
    )
    assert st.clock_jump == 1 and st.missing_at_tick > 0
    liks = all_likelihoods(layout, fin)
    means, dets = run_sbe(layout, liks, "AVCP", 0)
    truth = np.array([vehicle.centre(t) for t in rec.ticks])
    err = np.linalg.norm(means - truth, axis=1)
    assert np.all(np.isfinite(means)) and np.all(dets > 0)
    assert err[2:].mean() < 1.5
