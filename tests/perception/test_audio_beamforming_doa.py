"""The delay-and-sum beamformer peaks at the true direction (Kushwaha 2010, Eq. 33)."""

import numpy as np
import pytest

from fusetrack.core.errors import ShapeError
from fusetrack.perception.audio_beamforming import (
    AUDIO_MESSAGE_BYTES,
    Beamformer,
    MicrophoneArray,
    beam_angles,
    beam_delays,
    pack_audio_message,
    unpack_audio_message,
)
from fusetrack.world.acoustics import harmonic_engine, propagate

FS = 100e3


def plane_wave(theta, n, rng, c=343.0):
    """Far-field broadband plane wave from direction theta at the 4 microphones (exact delays)."""
    array = MicrophoneArray.rectangle()
    u = np.array([np.cos(theta), np.sin(theta)])
    base = rng.standard_normal(n + 200)
    spec = np.fft.rfft(base)
    f = np.fft.rfftfreq(base.size, 1 / FS)
    spec[(f < 200) | (f > 4000)] = 0
    out = []
    for p in array.offsets:
        delay = -(p @ u) / c  # arrival relative to the array centre
        out.append(np.fft.irfft(spec * np.exp(-2j * np.pi * f * delay), base.size)[100 : 100 + n])
    return np.array(out)


def test_delay_table_is_symmetric_and_bounded():
    d = beam_delays(MicrophoneArray.rectangle(), 36, FS, 343.0)
    assert d.shape == (36, 4) and d.min() == 0
    # the longest lag is the 11.7 cm diagonal: ≈ 34 samples at 100 kHz
    assert d.max() <= round(np.hypot(0.1, 0.06) * FS / 343.0)
    # opposite beams use mirrored delays
    assert np.array_equal(d[0], d[18][[2, 3, 0, 1]])


@pytest.mark.parametrize("theta_deg", [0.0, 37.0, 95.0, 181.0, 263.0, 333.0])
def test_peak_at_true_direction_for_plane_wave(theta_deg):
    rng = np.random.default_rng(int(theta_deg))
    bf = Beamformer(alpha=0.0, filter_band=None)
    x = plane_wave(np.deg2rad(theta_deg), bf.window + bf.preroll, rng)
    est = np.rad2deg(beam_angles()[np.argmax(bf.energies(x))])
    assert abs((est - theta_deg + 180) % 360 - 180) <= 5.0 + 1e-9


def test_moving_engine_source_is_found_by_rotated_node():
    rng = np.random.default_rng(3)
    array = MicrophoneArray.rectangle()
    heading = 1.2
    mics = array.world_positions((0.0, 0.0), heading)
    em = harmonic_engine(0.6, rng, FS, f0=45.0)
    bf = Beamformer(array, alpha=0.0)
    times = 0.3 + np.arange(bf.window + bf.preroll) / FS
    path = lambda t: np.column_stack([8.0 + 10.0 * t, np.full(t.size, 6.0)])  # noqa: E731
    x = propagate(em, path, mics, times, FS)
    est = beam_angles()[np.argmax(bf.energies(x))] + heading
    mid = path(np.array([times.mean() - 0.03]))[0]
    truth = np.arctan2(mid[1], mid[0])
    assert abs((est - truth + np.pi) % (2 * np.pi) - np.pi) <= np.deg2rad(10.0)


def test_smoothing_follows_eq_22():
    bf = Beamformer(alpha=0.5, filter_band=None)
    rng = np.random.default_rng(1)
    n = bf.window + bf.preroll
    a, b = rng.standard_normal((4, n)), 2 * rng.standard_normal((4, n))
    first = bf.process(a)
    second = bf.process(b)
    assert np.allclose(second, 0.5 * first + 0.5 * bf.energies(b))


def test_silent_microphone_is_counted_and_beams_still_form():
    rng = np.random.default_rng(2)
    bf = Beamformer(alpha=0.0, filter_band=None)
    x = plane_wave(np.deg2rad(120.0), bf.window + bf.preroll, rng)
    x[1] = 0.0
    e = bf.energies(x)
    assert bf.dead_channel_events == 1 and np.all(np.isfinite(e)) and e.max() > 0
    x[:] = np.nan
    assert np.all(bf.energies(x) == 0)
    with pytest.raises(ShapeError):
        bf.energies(x[:3])


def test_message_is_83_bytes_and_round_trips():
    e = np.linspace(0, 3e6, 36)
    msg = pack_audio_message(7, 513, 123456789, 4321, e)
    assert len(msg) == AUDIO_MESSAGE_BYTES == 83
    node, seq, t, elapsed, back = unpack_audio_message(msg)
    assert (node, seq, t, elapsed) == (7, 513, 123456789, 4321)
    assert np.allclose(back, e, rtol=0, atol=2**6)  # 16-bit quantisation after the shift
    with pytest.raises(ShapeError):
        unpack_audio_message(msg[:-1])
