"""Azimuth and polar angle from sound: a simulated 3-D microphone array and a standard DOA method.

Beyond the paper (Lee 2009 used a gradient-flow acoustic localiser, Stanacevic & Cauwenberghs
2005, whose angles the dissertation models as Gaussian noise). Here a small non-planar array
(six microphones on the axes, an octahedron of radius ``radius``) hears a white-noise source in
free field or in a shoebox room (pyroomacoustics image-source simulation), sensor noise is added
at ``snr_db``, and a frequency-domain DOA method from pyroomacoustics (normalised MUSIC by default; SRP-PHAT, whose
pyroomacoustics implementation loops over the grid in Python, is much slower) scans a
grid of azimuths and colatitudes. The result is one ``(azimuth, polar angle)`` pair per frame, in
the same convention as :class:`fusetrack.sensors.doa_projection.DoaSensor3D`, so the trackers run
on it unchanged.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core import ConfigError, invalid

Array = np.ndarray

ALGORITHMS = ("music-grid", "SRP", "MUSIC", "NormMUSIC")
SPEED_OF_SOUND = 343.0


FREQ_RANGE = (300.0, 3500.0)


def _steer(array: AudioDoaArray, az: Array, col: Array) -> tuple[Array, Array]:
    """Steering vectors ``(F, G, M)`` of directions (az, col) in the analysis band, and the bins."""
    u = np.stack([np.sin(col) * np.cos(az), np.sin(col) * np.sin(az), np.cos(col)], axis=1)
    mics = array.microphones()
    rel = mics - mics.mean(axis=1, keepdims=True)  # (3, M)
    bins = np.arange(array.nfft // 2 + 1)
    freqs = bins * array.fs / array.nfft
    keep = (freqs >= FREQ_RANGE[0]) & (freqs <= FREQ_RANGE[1])
    delay = u @ rel / SPEED_OF_SOUND  # (G, M): a plane wave from u reaches mic m earlier by u.r/c
    return np.exp(2j * np.pi * freqs[keep][:, None, None] * delay[None]), bins[keep]


@functools.lru_cache(maxsize=8)
def _coarse_grid(array: AudioDoaArray) -> tuple[Array, Array, Array, Array]:
    step = max(4.0, array.grid_deg)
    az = np.deg2rad(np.arange(0.0, 360.0, step))
    col = np.deg2rad(np.arange(0.0, 180.0 + 1e-9, step))
    A, C = (g.ravel() for g in np.meshgrid(az, col, indexing="ij"))
    steer, bins = _steer(array, A, C)
    return A, C, steer, bins


def _pseudo_spectrum(En: Array, steer: Array) -> Array:
    proj = np.einsum("fgm,fmk->fgk", steer.conj(), En)
    p = 1.0 / np.maximum(np.sum(np.abs(proj) ** 2, axis=-1), 1e-12)  # (F, G)
    return (p / p.max(axis=1, keepdims=True)).sum(axis=0)


def _music_grid(array: AudioDoaArray, frames: Array) -> Array:
    """Narrowband MUSIC (Schmidt 1986) for one source, normalised per bin and summed over the band.

    ``frames`` ``(M, F_all, S)`` STFT; per bin the noise subspace ``E_n`` of the spatial
    covariance and the pseudo-spectrum ``1 / |E_n^H a|^2``; searched on a 4-degree grid, then on a
    ``grid_deg`` grid within +-4 degrees of the coarse peak.
    """
    az, col, steer, bins = _coarse_grid(array)
    X = frames[:, bins, :]  # (M, F, S)
    R = np.einsum("mfs,nfs->fmn", X, X.conj()) / X.shape[2]
    _, vecs = np.linalg.eigh(R)  # ascending eigenvalues
    En = vecs[..., :-1]  # all but the largest: one source
    g = int(np.argmax(_pseudo_spectrum(En, steer)))
    step = np.deg2rad(array.grid_deg)
    offs = np.arange(-4.0, 4.0 + 1e-9, array.grid_deg) * math.pi / 180.0
    A, C = (v.ravel() for v in np.meshgrid(az[g] + offs, col[g] + offs, indexing="ij"))
    C = np.clip(C, 0.0, math.pi)
    fine, _ = _steer(array, A, C)
    h = int(np.argmax(_pseudo_spectrum(En, fine)))
    del step
    return np.array([A[h] % (2 * math.pi), C[h]])


@functools.lru_cache(maxsize=8)
def _doa_estimator(array: AudioDoaArray) -> Any:
    """The pyroomacoustics DOA object of an array (its grid and neighbours are built once)."""
    import pyroomacoustics as pra

    mics = array.microphones()
    az = np.deg2rad(np.arange(0.0, 360.0, array.grid_deg))
    col = np.deg2rad(np.arange(0.0, 180.0 + 1e-9, array.grid_deg))
    return pra.doa.algorithms[array.algorithm](
        mics - mics.mean(axis=1, keepdims=True), array.fs, array.nfft, c=343.0, num_src=1, dim=3,
        azimuth=az, colatitude=col,
    )  # fmt: skip


@dataclass(frozen=True)
class AudioDoaArray:
    """A simulated 6-microphone octahedral array at ``centre`` and its DOA estimator."""

    centre: tuple[float, float, float] = (0.0, 0.0, 0.0)
    radius: float = 0.08
    fs: int = 16_000
    nfft: int = 128
    frame_seconds: float = 0.032
    snr_db: float = 10.0
    algorithm: str = "music-grid"
    grid_deg: float = 0.5
    room: tuple[float, float, float] | None = None  # None: free field
    max_order: int = 3
    absorption: float = 0.6

    def __post_init__(self) -> None:
        if self.algorithm not in ALGORITHMS:
            raise ConfigError(invalid("algorithm", self.algorithm, f"one of {ALGORITHMS}"))
        if not (self.radius > 0 and self.grid_deg > 0 and self.frame_seconds > 0):
            raise ConfigError(
                invalid(
                    "radius/grid_deg/frame_seconds",
                    (self.radius, self.grid_deg, self.frame_seconds),
                    "> 0",
                )
            )

    def microphones(self) -> Array:
        """``(3, 6)`` microphone positions."""
        c = np.asarray(self.centre, float)[:, None]
        offsets = np.hstack([np.eye(3), -np.eye(3)]) * self.radius
        return c + offsets

    def estimate(self, source: Array, rng: np.random.Generator) -> Array:
        """``(azimuth, polar)`` of one frame of a white-noise source at ``source`` (global, m)."""
        import pyroomacoustics as pra  # optional heavy import

        src = np.asarray(source, float)
        mics = self.microphones()
        n = int(self.fs * self.frame_seconds)
        signal = rng.standard_normal(n)
        if self.room is None:
            room = pra.AnechoicRoom(dim=3, fs=self.fs, sigma2_awgn=None)
        else:
            room = pra.ShoeBox(
                list(self.room),
                fs=self.fs,
                materials=pra.Material(self.absorption),
                max_order=self.max_order,
            )
        room.add_source(src, signal=signal)
        room.add_microphone_array(pra.MicrophoneArray(mics, self.fs))
        room.simulate()
        x = room.mic_array.signals
        power = np.mean(x**2)
        x = x + math.sqrt(power / 10 ** (self.snr_db / 10)) * rng.standard_normal(x.shape)
        frames = np.array(
            [pra.transform.stft.analysis(ch, self.nfft, self.nfft // 2).T for ch in x]
        )
        if self.algorithm == "music-grid":
            return _music_grid(self, frames)
        doa = _doa_estimator(self)
        doa.locate_sources(frames, freq_range=list(FREQ_RANGE))
        return np.array(
            [float(doa.azimuth_recon[0]) % (2 * math.pi), float(doa.colatitude_recon[0])]
        )

    def measure(self, positions: Array, rng: np.random.Generator) -> Array:
        """One ``(azimuth, polar)`` per row of ``positions`` ``(T, 3)``: ``(T, 2)``."""
        return np.array([self.estimate(p, rng) for p in np.asarray(positions, float)])
