"""Delay-and-sum beamforming of a small microphone array into a detection function (Kushwaha 2010, Ch. III).

The acoustic node of the paper is a 4-microphone array (corners of a 10 cm × 6 cm rectangle) on
an FPGA that samples at 100 kHz, filters, delays each channel by an integer number of samples
per beam, sums the four channels and accumulates the power of the sum for 36 beams 10° apart
(Kushwaha 2010, Eq. 33, ``r_α[n] = Σ_p r_p[n + t_pq(α)]`` with ``t_pq(α) = d_pq cos(α - β_pq) f_s / C``;
the Ch. IV FPGA accumulates 2^14 samples). The beam energies, smoothed over time by
``λ_t = α λ_{t-1} + (1 - α) μ`` (Eq. 22), are the node's detection function λ(θ), sent in an
83-byte radio message (72 bytes for 36 16-bit energies).

Sign convention (the paper leaves it open; spec 003 A-III-3): a plane wave from direction
u(α) = (cos α, sin α) reaches microphone p at Δ_p = -(p · u)/C relative to the array centre, so
mic p is *advanced* by Δ_p: ``r_α[n] = Σ_p r_p[n + round((Δ_p - min_q Δ_q) f_s)]``. A source at
bearing θ then gives the largest energy at the beam nearest θ (tested).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import butter, sosfilt

from ..core import ConfigError, ShapeError, invalid

SPEED_OF_SOUND = 343.0  # m/s at 20 °C (spec 003 §7.2: 343 m/s for Ch. III)
AUDIO_MESSAGE_BYTES = 83  # Kushwaha 2010, Ch. III: node ID, sequence number, timestamps + 72 bytes


@dataclass(frozen=True, eq=False)
class MicrophoneArray:
    """Microphone positions ``offsets (P, 2)`` in the node frame (metres, x along the heading)."""

    offsets: NDArray[np.float64]

    def __post_init__(self) -> None:
        o = np.asarray(self.offsets, float)
        if o.ndim != 2 or o.shape[1] != 2 or o.shape[0] < 2:
            raise ShapeError(invalid("offsets.shape", o.shape, "(P, 2) with P >= 2"))
        object.__setattr__(self, "offsets", o)

    @classmethod
    def rectangle(cls, width: float = 0.10, height: float = 0.06) -> MicrophoneArray:
        """Four microphones at the corners of a ``width × height`` rectangle (paper: 10 × 6 cm)."""
        w, h = width / 2, height / 2
        return cls(np.array([[w, h], [-w, h], [-w, -h], [w, -h]]))

    @property
    def n_mics(self) -> int:
        return self.offsets.shape[0]

    def world_positions(self, node_xy: ArrayLike, heading: float) -> NDArray[np.float64]:
        """Microphone positions ``(P, 2)`` in the world for a node at ``node_xy`` facing ``heading``."""
        c, s = np.cos(heading), np.sin(heading)
        rot = np.array([[c, -s], [s, c]])
        return np.asarray(node_xy, float)[:2] + self.offsets @ rot.T


def beam_angles(n_beams: int = 36) -> NDArray[np.float64]:
    """θ_i = i · 2π / M, i = 0..M-1 (Kushwaha 2010, Ch. III: M = 36, 10° resolution)."""
    return 2 * np.pi * np.arange(n_beams) / n_beams


def beam_delays(
    array: MicrophoneArray, n_beams: int = 36, fs: float = 100e3, c: float = SPEED_OF_SOUND
) -> NDArray[np.int64]:
    """Integer advances ``(n_beams, P)`` ≥ 0 of each microphone per beam (the FPGA lookup table).

    Kushwaha 2010, Eq. 33 / Ch. IV: ``t_pq(α) = round(d_pq cos(α - β_pq) f_s / C)``; written here as
    ``round((Δ_p(α) - min_q Δ_q(α)) f_s)`` with ``Δ_p(α) = -(p · u(α)) / C`` (same numbers up to the
    common reference shift, which does not change the energy)."""
    a = beam_angles(n_beams)
    u = np.stack([np.cos(a), np.sin(a)], axis=1)  # (B, 2)
    arrival = -(u @ array.offsets.T) / c  # (B, P)
    d = np.round((arrival - arrival.min(axis=1, keepdims=True)) * fs).astype(np.int64)
    return d


def bandpass(
    signals: ArrayLike, fs: float = 100e3, low: float = 100.0, high: float = 4000.0
) -> NDArray[np.float64]:
    """The beamformer's noise filter (unspecified in the paper; spec 003 [C]: 4th-order
    Butterworth band-pass 100 Hz – 4 kHz), applied along the last axis."""
    sos = butter(4, [low, high], btype="bandpass", fs=fs, output="sos")
    return sosfilt(sos, np.asarray(signals, float), axis=-1)


def delay_and_sum_energy(
    signals: ArrayLike, delays: ArrayLike, length: int | None = None
) -> NDArray[np.float64]:
    """Beam energies ``B(α) = Σ_n (Σ_p r_p[n + t_p(α)])²`` over ``length`` samples (Kushwaha 2010, Eq. 33
    and the Ch. IV FPGA accumulator). ``signals (P, L + max delay)``; returns ``(n_beams,)``.
    Per-sample mean power rather than the raw sum, so windows of any length compare."""
    x = np.asarray(signals, float)
    d = np.asarray(delays, np.int64)
    if x.ndim != 2 or d.ndim != 2 or d.shape[1] != x.shape[0]:
        raise ShapeError(
            invalid("signals/delays", (x.shape, d.shape), "(P, L) signals and (B, P) delays")
        )
    n = x.shape[1] - int(d.max()) if length is None else int(length)
    if n <= 0 or n + int(d.max()) > x.shape[1]:
        raise ShapeError(
            invalid(
                "signals.shape[1]", x.shape[1], f"at least length + max delay = {n + int(d.max())}"
            )
        )
    out = np.empty(d.shape[0])
    for b, row in enumerate(d):
        s = x[0, row[0] : row[0] + n].copy()
        for p in range(1, x.shape[0]):
            s += x[p, row[p] : row[p] + n]
        out[b] = np.einsum("i,i->", s, s) / n  # not BLAS: no thread start-up per beam
    return out


@dataclass
class Beamformer:
    """One acoustic node's processing: filter, delay-and-sum over ``window`` samples, smoothing.

    ``process(signals)`` takes the last ``window + pre-roll`` samples of the four channels (the
    pre-roll absorbs the filter transient and the delays) and returns the smoothed detection
    function λ(θ_i) (Kushwaha 2010, Eq. 22 with averaging factor ``alpha``). A silent or dead
    microphone (all-zero or non-finite channel) is dropped from the sum and counted in
    ``dead_channel_events``; the remaining channels still form beams.
    """

    array: MicrophoneArray = field(default_factory=MicrophoneArray.rectangle)
    n_beams: int = 36
    fs: float = 100e3
    window: int = 2**14
    alpha: float = 0.5
    c: float = SPEED_OF_SOUND
    filter_band: tuple[float, float] | None = (100.0, 4000.0)
    state: NDArray[np.float64] | None = None
    dead_channel_events: int = 0

    def __post_init__(self) -> None:
        if not 0 <= self.alpha < 1:
            raise ConfigError(invalid("alpha", self.alpha, "a number in [0, 1)"))
        self._delays = beam_delays(self.array, self.n_beams, self.fs, self.c)

    @property
    def preroll(self) -> int:
        return (
            int(self._delays.max()) + 2000
        )  # 20 ms: the FPGA FIFO depth, also the filter transient

    def energies(self, signals: ArrayLike) -> NDArray[np.float64]:
        x = np.asarray(signals, float)
        if x.shape[0] != self.array.n_mics:
            raise ShapeError(
                invalid("signals.shape[0]", x.shape[0], f"{self.array.n_mics} channels")
            )
        alive = np.all(np.isfinite(x), axis=1) & (np.abs(x).max(axis=1) > 0)
        if not np.all(alive):
            self.dead_channel_events += int(np.sum(~alive))
            if not np.any(alive):
                return np.zeros(self.n_beams)
            x = np.where(alive[:, None], np.nan_to_num(x), 0.0)
        if self.filter_band is not None:
            x = bandpass(x, self.fs, *self.filter_band)
        x = x[:, -(self.window + int(self._delays.max())) :]
        return delay_and_sum_energy(x[alive], self._delays[:, alive], self.window)

    def process(self, signals: ArrayLike) -> NDArray[np.float64]:
        mu = self.energies(signals)
        # Kushwaha 2010, Eq. 22: λ_t = α λ_{t-1} + (1 - α) μ
        self.state = mu if self.state is None else self.alpha * self.state + (1 - self.alpha) * mu
        return self.state.copy()


def pack_audio_message(
    node_id: int, seq: int, event_time_us: int, elapsed_us: int, energies: ArrayLike
) -> bytes:
    """The 83-byte detection message: node (u8), sequence (u16), scale shift (u8), event time
    (u32, µs, node clock), elapsed-time field (u24, µs, for hop-by-hop time translation) and 36
    16-bit beam energies ``uint16(E >> s)`` with the smallest shift s that fits (spec 003 A-III-4)."""
    e = np.asarray(energies, float)
    if e.shape != (36,):
        raise ShapeError(invalid("energies.shape", e.shape, "(36,)"))
    ints = np.round(np.clip(e, 0, None)).astype(np.uint64)
    shift = 0
    while int(ints.max() >> np.uint64(shift)) > 0xFFFF:
        shift += 1
    q = (ints >> np.uint64(shift)).astype("<u2")
    head = struct.pack(
        "<BHBI", node_id & 0xFF, seq & 0xFFFF, shift, event_time_us & 0xFFFFFFFF
    ) + int(elapsed_us & 0xFFFFFF).to_bytes(3, "little")
    msg = head + q.tobytes()
    assert len(msg) == AUDIO_MESSAGE_BYTES
    return msg


def unpack_audio_message(msg: bytes) -> tuple[int, int, int, int, NDArray[np.float64]]:
    """Inverse of :func:`pack_audio_message`: (node, seq, event time µs, elapsed µs, energies)."""
    if len(msg) != AUDIO_MESSAGE_BYTES:
        raise ShapeError(invalid("len(message)", len(msg), f"{AUDIO_MESSAGE_BYTES} bytes"))
    node, seq, shift, t = struct.unpack("<BHBI", msg[:8])
    elapsed = int.from_bytes(msg[8:11], "little")
    e = np.frombuffer(msg[11:], "<u2").astype(float) * float(2**shift)
    return node, seq, t, elapsed, e
