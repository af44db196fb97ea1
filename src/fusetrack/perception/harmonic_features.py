"""The two acoustic features of one Ch. IV node: the beamform and the compressed PSD (Kushwaha 2010).

* Beamform (Eq. 33): delay-and-sum energies of ``Q`` beams over the whole window, through the
  Ch. III front end (:mod:`fusetrack.perception.audio_beamforming`: the integer delay table of the
  FPGA and its sum of squares). Eq. 33 has no band-pass filter, so none is applied here.
* PSD (Ch. IV "Acoustic PSD", FPGA [L2016]): one microphone, decimated to 4 kHz by a polyphase
  filter, the last 1 s (``n_fft`` = 4000 samples: 1 Hz bins, spec 003 A-IV-2), ``P = Y·conj(Y)``,
  one half; compressed to the ``n_peaks`` (= 30 on the FPGA) bins of largest power, sent as
  (frequency, power) pairs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.signal import resample_poly

from ..core import ConfigError, ShapeError, invalid
from .audio_beamforming import MicrophoneArray, beam_delays, delay_and_sum_energy


@dataclass(frozen=True, eq=False)
class CompressedPsd:
    """The ``N_PSD`` strongest PSD bins: ``freqs`` (Hz, ascending) and their ``powers``."""

    freqs: np.ndarray
    powers: np.ndarray
    resolution: float = 1.0  # Hz per bin

    def __post_init__(self) -> None:
        f = np.asarray(self.freqs, float)
        p = np.asarray(self.powers, float)
        if f.shape != p.shape or f.ndim != 1:
            raise ShapeError(invalid("freqs/powers", (f.shape, p.shape), "two equal 1-D shapes"))
        order = np.argsort(f)
        object.__setattr__(self, "freqs", f[order])
        object.__setattr__(self, "powers", np.nan_to_num(p[order], nan=0.0, posinf=0.0))


@dataclass(frozen=True, eq=False)
class NodeFeatures:
    """What one Ch. IV node sends: ``beamform (Q,)`` (mean power per sample per beam) and its PSD."""

    beamform: np.ndarray
    psd: CompressedPsd


def psd(
    signal: ArrayLike, fs: float = 100e3, rate: float = 4000.0, n_fft: int = 4000
) -> tuple[np.ndarray, np.ndarray]:
    """``(freqs, P)`` of the last ``n_fft`` samples after decimation from ``fs`` to ``rate``
    (Kushwaha 2010, Ch. IV: ``P(ω) = Y(ω)·conj(Y(ω))``, ``Y = FFT(r, N_FFT)``, one half kept)."""
    x = np.asarray(signal, float)
    ratio = fs / rate
    if abs(ratio - round(ratio)) > 1e-9 or ratio < 1:
        raise ConfigError(invalid("fs/rate", ratio, "an integer decimation factor >= 1"))
    y = resample_poly(x, 1, round(ratio)) if ratio > 1 else x
    if y.size < n_fft:
        raise ShapeError(invalid("signal length", x.size, f">= {n_fft} samples at {rate} Hz"))
    spec = np.fft.rfft(y[-n_fft:], n_fft)
    return np.fft.rfftfreq(n_fft, 1 / rate), (spec * spec.conj()).real


def compress_psd(
    freqs: ArrayLike, powers: ArrayLike, n_peaks: int = 30, f_min: float = 1.0
) -> CompressedPsd:
    """Keep the ``n_peaks`` bins of largest power at or above ``f_min`` (DC is not sent)."""
    f = np.asarray(freqs, float)
    p = np.asarray(powers, float)
    if n_peaks < 1:
        raise ConfigError(invalid("n_peaks", n_peaks, "an integer >= 1"))
    ok = np.flatnonzero(f >= f_min)
    top = ok[np.argsort(p[ok])[::-1][:n_peaks]]
    res = float(f[1] - f[0]) if f.size > 1 else 1.0
    return CompressedPsd(f[top], p[top], res)


def beamform(
    signals: ArrayLike,
    array: MicrophoneArray,
    *,
    n_beams: int = 36,
    fs: float = 100e3,
    c: float = 350.0,
    length: int | None = None,
) -> np.ndarray:
    """Beam energies ``B(α)`` (Eq. 33) per sample over ``length`` samples (default: all that the
    delays leave), using the FPGA's integer delay table."""
    d = beam_delays(array, n_beams, fs, c)
    return delay_and_sum_energy(signals, d, length)


def node_features(
    signals: ArrayLike,
    array: MicrophoneArray,
    *,
    n_beams: int = 36,
    fs: float = 100e3,
    c: float = 350.0,
    psd_rate: float = 4000.0,
    n_fft: int = 4000,
    n_peaks: int = 30,
    psd_mic: int = 0,
) -> NodeFeatures:
    """Both features of one node from its microphone signals ``(P, L)``."""
    x = np.asarray(signals, float)
    f, p = psd(x[psd_mic], fs, psd_rate, n_fft)
    return NodeFeatures(
        beamform(x, array, n_beams=n_beams, fs=fs, c=c), compress_psd(f, p, n_peaks)
    )


def harmonicity(
    freqs: ArrayLike, powers: ArrayLike, f0s: ArrayLike, *, f_max: float = 1000.0, tol: float = 1.0
) -> float:
    """Share of PSD power at the harmonics of ``f0s`` (Kushwaha 2010, Eq. 59), over bins ≤ ``f_max``."""
    f = np.asarray(freqs, float)
    p = np.asarray(powers, float)
    band = (f > 0) & (f <= f_max)
    total = float(p[band].sum())
    if total <= 0:
        return 0.0
    return float(p[band & harmonic_mask(f, f0s, f_max=f_max, tol=tol)].sum()) / total


def harmonic_mask(
    freqs: ArrayLike, f0s: ArrayLike, *, f_max: float = 1000.0, tol: float = 1.0
) -> np.ndarray:
    """``ω_j ∈ ℍ(Ω_f)``: closer than ``tol`` Hz to some ``h·f0`` ≤ ``f_max`` (Eq. 40's harmonic
    set; one 1 Hz bin either side: the main lobe of a line seen through a 1 s window)."""
    f = np.asarray(freqs, float)[..., None]
    f0 = np.asarray(f0s, float).reshape(-1)
    if f0.size == 0:
        return np.zeros(f.shape[:-1], bool)
    h = np.maximum(np.round(f / f0), 1.0)
    return np.asarray(np.any((np.abs(f - h * f0) < tol) & (h * f0 <= f_max + tol), axis=-1))
