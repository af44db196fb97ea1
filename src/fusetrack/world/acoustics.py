"""Free-field sound for simulated microphone arrays: sources, propagation, noise.

Spec 003 §6 substitutes the paper's street recordings by synthetic sound: a vehicle is a harmonic
engine (fundamental 30–80 Hz, harmonics to 1 kHz) plus broadband tyre noise; a speaker is
band-limited noise with a syllabic envelope and a voiced harmonic part. A microphone at distance
r(t) hears ``s(t - r/C) / r`` (spherical spreading, propagation delay; Kushwaha 2010, Eq. 6 with
α = 1 for pressure). Moving sources are handled by a fractional-delay propagator: the emitted
signal is sampled at 100 kHz and read back at the retarded time by linear interpolation, which
also produces the Doppler shift. Background noise is pink and independent per microphone.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import butter, lfilter, sosfilt

SPEED_OF_SOUND = 343.0


def pink_noise(shape: tuple[int, ...], rng: np.random.Generator) -> NDArray[np.float64]:
    """Unit-variance 1/f noise along the last axis: white noise through P. Kellet's 3-pole
    pinking filter (within ±0.05 dB of 1/f above 10 Hz at 44.1 kHz; a 1/f-like slope here)."""
    b = [0.049922035, -0.095993537, 0.050612699, -0.004408786]
    a = [1.0, -2.494956002, 2.017265875, -0.522189400]
    x = lfilter(b, a, rng.standard_normal(shape), axis=-1)
    return x / np.maximum(x.std(axis=-1, keepdims=True), 1e-12)


def harmonic_engine(
    duration: float,
    rng: np.random.Generator,
    fs: float = 100e3,
    f0: float = 50.0,
    f_max: float = 1000.0,
    tyre_level: float = 0.5,
) -> NDArray[np.float64]:
    """A vehicle's emitted sound (unit RMS at 1 m), starting at t = 0.

    Harmonics k·f0 ≤ f_max with amplitudes ∝ 1/√k and random phases, a slow ±2 % wobble of f0,
    plus broadband tyre/road noise (300 Hz – 3 kHz) at ``tyre_level`` of the harmonic RMS."""
    n = round(duration * fs)
    t = np.arange(n) / fs
    wobble = 1 + 0.02 * np.sin(2 * np.pi * rng.uniform(0.2, 0.6) * t + rng.uniform(0, 2 * np.pi))
    phase = 2 * np.pi * np.cumsum(f0 * wobble) / fs
    x = np.zeros(n)
    for k in range(1, int(f_max // f0) + 1):
        x += np.sin(k * phase + rng.uniform(0, 2 * np.pi)) / np.sqrt(k)
    x /= x.std()
    sos = butter(4, [300.0, 3000.0], btype="bandpass", fs=fs, output="sos")
    tyre = sosfilt(sos, rng.standard_normal(n))
    x = x + tyre_level * tyre / tyre.std()
    return x / x.std()


def speech_like(
    duration: float, rng: np.random.Generator, fs: float = 100e3
) -> NDArray[np.float64]:
    """Speech-like sound (unit RMS at 1 m): a voiced harmonic part (f0 100–200 Hz) and
    300 Hz – 3.4 kHz noise, both under a 4 Hz syllabic envelope."""
    n = round(duration * fs)
    t = np.arange(n) / fs
    f0 = rng.uniform(100, 200)
    voiced = sum(np.sin(2 * np.pi * k * f0 * t + rng.uniform(0, 6.3)) / k for k in range(1, 20))
    sos = butter(4, [300.0, 3400.0], btype="bandpass", fs=fs, output="sos")
    noise = sosfilt(sos, rng.standard_normal(n))
    envelope = 0.55 + 0.45 * np.sin(2 * np.pi * 4.0 * t + rng.uniform(0, 6.3))
    x = envelope * (voiced / np.std(voiced) + 0.7 * noise / noise.std())
    return x / x.std()


def propagate(
    emission: ArrayLike,
    source_path: Callable[[NDArray[np.float64]], NDArray[np.float64]],
    mics: ArrayLike,
    times: ArrayLike,
    fs: float = 100e3,
    c: float = SPEED_OF_SOUND,
    min_distance: float = 0.2,
) -> NDArray[np.float64]:
    """Pressure at each microphone ``(M, L)`` at ``times (L,)`` (seconds since the emission's t = 0).

    ``source_path(t)`` gives the source position ``(L, 2|3)`` at times ``t``; ``mics (M, 2|3)``.
    The retarded time τ solves τ = t - |m - s(τ)|/C; one fixed-point step from τ = t - r(t)/C is
    exact to (v/C)² (≈ 10⁻³ for a car). Samples before the emission starts are 0."""
    e = np.asarray(emission, float)
    t = np.asarray(times, float)
    m = np.atleast_2d(np.asarray(mics, float))
    src_now = source_path(t)
    dim = min(src_now.shape[-1], m.shape[-1])
    mic = m[:, None, :dim]
    r = np.sqrt(((src_now[None, :, :dim] - mic) ** 2).sum(-1))  # (M, L)
    # one fixed-point step: the source position at the retarded time (mean over the mics)
    tau_centre = t - r.mean(axis=0) / c
    r = np.sqrt(((source_path(tau_centre)[None, :, :dim] - mic) ** 2).sum(-1))
    u = (t[None, :] - r / c) * fs
    i0 = np.floor(u).astype(np.int64)
    frac = u - i0
    ok = (i0 >= 0) & (i0 + 1 < e.size)
    i0 = np.clip(i0, 0, e.size - 2)
    out = (1 - frac) * e[i0] + frac * e[i0 + 1]  # fractional delay: linear interpolation
    return np.where(ok, out, 0.0) / np.maximum(r, min_distance)
