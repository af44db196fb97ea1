"""Stationary harmonic sound sources and their free-field propagation (Kushwaha 2010, Ch. IV).

A source is a point at ``position`` emitting a harmonic signal: energy only at multiples of its
fundamental ``f0`` (Eq. 34, ``P_s(ω) = Σ_h ψ_h δ(ω - h ω_f)``), optionally plus band-limited noise
(the harmonicity relaxation, Eq. 59) and a directional gain ``((2 + cos φ)/3)^β`` (the directivity
relaxation, Ch. IV "Directivity"; applied to the amplitude, spec 003 A-IV-12). A microphone at
``x_p`` receives ``Σ_m λ_p^(m) s^(m)[n - τ_p^(m)] + w_p[n]`` with ``λ_p^(m) = d_0/‖x_p - x^(m)‖`` and
``τ_p^(m) = ‖x_p - x^(m)‖/C`` (Eq. 32).

Delays are exact (not rounded to samples): each harmonic is a complex exponential whose phase
is shifted per microphone, and the noise part is delayed in the frequency domain (a circular
shift of stationary noise, itself a valid noise realisation).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, ShapeError, invalid

SPEED_OF_SOUND_CH4 = 350.0  # m/s, Kushwaha 2010 Table 10
NOISE_BAND = (20.0, 1000.0)  # Hz: a source's non-harmonic part lies in the band of its harmonics


@dataclass(frozen=True, eq=False)
class HarmonicSource:
    """One stationary source: harmonic powers ``energies[h-1]`` (mean square at ``d0``) of the
    harmonics ``h·f0``, their ``phases``, a non-harmonic noise power ``noise_power`` (at ``d0``),
    and a facing direction with directionality coefficient ``directivity`` (β = 0: omnidirectional).
    """

    position: np.ndarray
    f0: float
    energies: np.ndarray
    phases: np.ndarray = field(default_factory=lambda: np.zeros(0))
    noise_power: float = 0.0
    facing: float = 0.0
    directivity: float = 0.0

    def __post_init__(self) -> None:
        pos = np.asarray(self.position, float)
        if pos.shape != (2,):
            raise ShapeError(invalid("position.shape", pos.shape, "(2,)"))
        e = np.asarray(self.energies, float)
        if e.ndim != 1 or e.size == 0 or np.any(e < 0) or not np.all(np.isfinite(e)):
            raise ConfigError(invalid("energies", e, "a non-empty 1-D array of powers >= 0"))
        ph = np.asarray(self.phases, float)
        if ph.size == 0:
            ph = np.zeros(e.size)
        if ph.shape != e.shape:
            raise ShapeError(invalid("phases.shape", ph.shape, f"{e.shape} like energies"))
        if not (np.isfinite(self.f0) and self.f0 > 0):
            raise ConfigError(invalid("f0", self.f0, "a frequency > 0 Hz"))
        if not self.noise_power >= 0:
            raise ConfigError(invalid("noise_power", self.noise_power, "a power >= 0"))
        if not self.directivity >= 0:
            raise ConfigError(invalid("directivity", self.directivity, "a coefficient β >= 0"))
        object.__setattr__(self, "position", pos)
        object.__setattr__(self, "energies", e)
        object.__setattr__(self, "phases", ph)

    @property
    def frequencies(self) -> np.ndarray:
        """Harmonic frequencies ``h·f0``, h = 1..H (Hz)."""
        return self.f0 * np.arange(1, self.energies.size + 1)

    @property
    def harmonicity(self) -> float:
        """Share of the emitted power at the harmonics (Kushwaha 2010, Eq. 59)."""
        total = float(self.energies.sum()) + self.noise_power
        return float(self.energies.sum()) / total if total > 0 else 0.0

    def gain(self, points: ArrayLike, d0: float = 1.0) -> np.ndarray:
        """Amplitude factor ``λ = d0/r · ((2 + cos φ)/3)^β`` towards ``points (..., 2)``
        (Eq. 32 attenuation times the Ch. IV directional attenuation)."""
        v = np.asarray(points, float) - self.position
        r = np.maximum(np.hypot(v[..., 0], v[..., 1]), 1e-3)
        g = d0 / r
        if self.directivity > 0:
            phi = np.arctan2(v[..., 1], v[..., 0]) - self.facing
            g = g * ((2.0 + np.cos(phi)) / 3.0) ** self.directivity
        return np.asarray(g)


def random_sources(
    n: int,
    rng: np.random.Generator,
    *,
    field_box: tuple[float, float, float, float] = (0.0, 10.0, 0.0, 5.0),
    f0_range: tuple[float, float] = (40.0, 200.0),
    min_f0_gap: float = 5.0,
    f_max: float = 1000.0,
    avoid: ArrayLike | None = None,
    min_distance: float = 1.0,
    harmonicity: float = 1.0,
    directivity: float = 0.0,
    positions: ArrayLike | None = None,
    f0s: Sequence[float] | None = None,
) -> list[HarmonicSource]:
    """``n`` sources as in spec 003 §3.5 [C]: uniform in ``field_box`` at least ``min_distance`` from
    the points ``avoid`` (the sensors), fundamentals uniform in ``f0_range`` and ``min_f0_gap`` apart,
    harmonic powers ∝ 1/h up to ``f_max`` with random phases, total power 1 at d0 (scaled so the
    harmonics hold the fraction ``harmonicity``), random facing directions."""
    if n < 1:
        raise ConfigError(invalid("n", n, "an integer >= 1"))
    if not 0 < harmonicity <= 1:
        raise ConfigError(invalid("harmonicity", harmonicity, "a fraction in (0, 1]"))
    x0, x1, y0, y1 = field_box
    pts = np.zeros((0, 2)) if avoid is None else np.asarray(avoid, float).reshape(-1, 2)
    if positions is not None:
        pos = np.asarray(positions, float).reshape(n, 2)
    else:
        rows: list[np.ndarray] = []
        while len(rows) < n:
            p = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
            if pts.size == 0 or np.min(np.hypot(*(pts - p).T)) >= min_distance:
                rows.append(p)
        pos = np.array(rows)
    if f0s is not None:
        f = np.asarray(f0s, float).reshape(n)
    else:
        f = np.zeros(0)
        while f.size < n:
            c = rng.uniform(*f0_range)
            if f.size == 0 or np.min(np.abs(f - c)) >= min_f0_gap:
                f = np.append(f, c)
    out = []
    for m in range(n):
        h = np.arange(1, int(f_max // f[m]) + 1)
        e = (1.0 / h) / np.sum(1.0 / h) * harmonicity
        out.append(
            HarmonicSource(
                pos[m],
                float(f[m]),
                e,
                rng.uniform(0, 2 * np.pi, h.size),
                noise_power=1.0 - harmonicity,
                facing=float(rng.uniform(0, 2 * np.pi)),
                directivity=directivity,
            )
        )
    return out


def received_signals(
    sources: Sequence[HarmonicSource],
    mics: ArrayLike,
    n_samples: int,
    rng: np.random.Generator,
    *,
    fs: float = 100e3,
    c: float = SPEED_OF_SOUND_CH4,
    d0: float = 1.0,
) -> np.ndarray:
    """Noise-free pressure ``(P, n_samples)`` at the microphones ``mics (P, 2)`` (Kushwaha 2010, Eq. 32).

    Harmonic ``h`` of source ``m`` arrives as ``λ_p √(2ψ_h) cos(2π h f0 (n/fs - τ_p) + φ_h)``; the
    noise part (power ``noise_power`` in ``NOISE_BAND``) is drawn once per source and delayed by
    ``τ_p`` in the frequency domain."""
    m_xy = np.asarray(mics, float)
    if m_xy.ndim != 2 or m_xy.shape[1] != 2:
        raise ShapeError(invalid("mics.shape", m_xy.shape, "(P, 2)"))
    t = np.arange(n_samples) / fs
    out = np.zeros((m_xy.shape[0], n_samples))
    freqs = np.fft.rfftfreq(n_samples, 1 / fs)
    for s in sources:
        r = np.hypot(*(m_xy - s.position).T)  # (P,)
        tau = r / c
        lam = s.gain(m_xy, d0)  # (P,)
        f = s.frequencies
        keep = f < fs / 2
        amp = np.sqrt(2 * s.energies[keep])
        # Σ_h Re(c_ph e^{j2π f_h t}) with c_ph = λ_p a_h e^{j(φ_h - 2π f_h τ_p)}: one complex GEMM
        coef = (
            lam[:, None]
            * amp[None, :]
            * np.exp(1j * (s.phases[keep] - 2 * np.pi * np.outer(tau, f[keep])))
        )
        basis = np.exp(2j * np.pi * np.outer(f[keep], t))
        out += (coef @ basis).real
        if s.noise_power > 0:
            band = (freqs >= NOISE_BAND[0]) & (freqs <= NOISE_BAND[1])
            spec = np.zeros(freqs.size, complex)
            spec[band] = rng.standard_normal(band.sum()) + 1j * rng.standard_normal(band.sum())
            noise = np.fft.irfft(spec, n_samples)
            spec *= np.sqrt(s.noise_power) / max(float(noise.std()), 1e-300)
            delayed = spec[None, :] * np.exp(-2j * np.pi * np.outer(tau, freqs))
            out += lam[:, None] * np.fft.irfft(delayed, n_samples, axis=1)
    return out


def noise_sigma(signals: ArrayLike, snr_db: float) -> float:
    """σ_w giving ``snr_db``: mean received signal power over all microphones / σ_w² (spec 003 §3.5 [C])."""
    power = float(np.mean(np.asarray(signals, float) ** 2))
    return float(np.sqrt(power / 10 ** (snr_db / 10)))
