"""Kushwaha 2010 fusion path: 16-bit audio messages (spec 003 A-III-4) and SBE track termination
(spec 003 §2.5 step 6: 4 quiet ticks end a track)."""

import numpy as np

from fusetrack.experiments.kushwaha2010.scene import (
    ADC_FULL_SCALE,
    FusionInput,
    audio_on_the_wire,
    track_end,
)
from fusetrack.management.fusion_scheduler import IntakeStats, Packet


def test_audio_on_the_wire_error_is_within_the_16_bit_bound():
    rng = np.random.default_rng(1)
    lam = rng.lognormal(np.log(0.05), 1.5, (50, 36))
    back = np.array([audio_on_the_wire(x) for x in lam])
    rel = np.abs(back - lam) / lam.max(axis=1, keepdims=True)
    # B >> s truncates: error < 2^s counts, and the smallest s that fits makes 2^s <= 2 max / 2^16
    assert rel.max() <= 2.0**-15 + 1e-12
    assert rel.max() > 0  # it is quantised, not passed through
    assert np.all(back <= lam + 1e-15)  # truncation never rounds up


def test_audio_on_the_wire_small_values_and_saturation():
    lsb2 = (ADC_FULL_SCALE / 128) ** 2
    one_count = lsb2 / 2**14  # mean power of a single count in the 2^14-sample sum
    lam = np.arange(36) * one_count  # max 35 counts: shift 0, exact
    np.testing.assert_allclose(audio_on_the_wire(lam), lam, rtol=0, atol=1e-18)
    loud = np.full(36, 1e3)  # beyond the 32-bit register: saturates, stays finite
    out = audio_on_the_wire(loud)
    assert np.all(np.isfinite(out))
    assert out.max() <= (2**32 - 1) * one_count * (1 + 1e-12)


def _fin(levels):
    taken = [
        {"A1": Packet("A1", k, 0.25 * k, np.full(36, v), 0.25 * k)} for k, v in enumerate(levels)
    ]
    return FusionInput(0.25 * np.arange(len(levels)), taken, IntakeStats())


def test_track_ends_after_four_quiet_ticks():
    loud, quiet = 2.0, 0.5
    levels = [loud] * 5 + [quiet] * 3 + [loud] + [quiet] * 4 + [loud] * 2
    assert track_end(_fin(levels), 1.0, start=0) == 13  # ticks 9-12 quiet: ends after tick 12
    assert track_end(_fin([loud] * 10), 1.0, start=0) == 10  # never quiet: lives to the end
    # a node that falls silent (no packet) counts as quiet
    fin = _fin([loud] * 3 + [quiet] * 6)
    for k in (3, 4):
        fin.taken[k] = {}
    assert track_end(fin, 1.0, start=0) == 7


def test_grid_track_ends_when_the_posterior_is_about_to_leave_the_field():
    from test_kushwaha2010_fusion_bad_input import synthetic_packets

    from fusetrack.experiments.kushwaha2010.scene import (
        Recording,
        VehiclePass,
        all_likelihoods,
        default_layout,
        fusion_input,
        run_sbe,
    )

    rng = np.random.default_rng(0)
    layout = default_layout()
    vehicle = VehiclePass(x0=1.0, lane_y=8.5, speed=10.0)  # leaves x = 35 m at t = 3.4 s
    times = np.arange(0.0, 5.0, 0.25)
    packets = synthetic_packets(layout, vehicle, times, rng)
    rec = Recording(packets, [vehicle], 0.0, 4.75, np.zeros(len(packets)), audio_threshold=0.0)
    fin = fusion_input(rec, rng, packet_loss=0.0)
    liks = all_likelihoods(layout, fin)
    means, _ = run_sbe(layout, liks, "AVCP", 0, end_at_exit=True)
    alive = np.flatnonzero(np.isfinite(means[:, 0]))
    exit_tick = int(np.searchsorted(rec.ticks, 3.4, side="right"))
    assert alive[-1] + 1 in range(exit_tick - 2, exit_tick + 2)
    kept, _ = run_sbe(layout, liks, "AVCP", 0)  # default: no termination, as before
    assert np.all(np.isfinite(kept))
