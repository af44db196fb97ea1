"""State partition with parallel EKFs (SP-PEKF, after Lainiotis) and PF-SP-PEKF (Zhai 2007, Ch. 3).

The bank (Zhai 2007, Sec. 3.1.1, Eqs. 15-30) runs N EKF "channels" on a state partition
``x = x_n + x_r``: a random nominal trajectory ``x_n`` propagated with its own noise draw, and a
residual ``x_r`` estimated by an EKF linearised at the nominal. The likelihood-weighted,
moment-matched mixture of the channels, ``N(x_total, R_total)``, is the proposal of PF-SP-PEKF
(Algorithm 1); after resampling, the particle estimate is fed back by re-partitioning every
channel, ``x_r <- x_PF - x_n``.

Choices (spec 001, Sec. 3 A0 and Sec. 6): nominals are drawn from the prior with zero residual
and zero residual covariance; the pseudo-innovation is ``z - h(x_n + x_r(t|t-1))`` as printed
(Eq. 27); channel weights are memoryless (``psi_i ∝ L_i``, as in every experiment); the residual
covariance is kept at the feedback. Covariance updates use the Joseph form. A channel whose
covariance stops being positive definite is repaired (eigenvalues clipped) and counted; a
channel with non-finite values gets weight 0 and is reset at the feedback (counted as dropped).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..core import (
    ConfigError,
    Gaussian,
    Measurement,
    MotionModel,
    SensorModel,
    UnknownSensorError,
    invalid,
)
from .proposals import Array, SISStats, Zs

_LOG_2PI = float(np.log(2 * np.pi))


@dataclass(frozen=True)
class BankState:
    """The belief of an :class:`SPPEKFBank`: ``nominal``, ``resid`` ``(..., C, d)``, the
    channels' residual covariances ``cov`` ``(..., C, d, d)``, their weights, and the
    moment-matched Gaussian ``N(mean, total_cov)`` of the bank."""

    nominal: Array
    resid: Array
    cov: Array
    log_psi: Array  # (..., C) normalised channel log-weights
    mean: Array  # (..., d)   x_total (Eq. 28)
    total_cov: Array  # (..., d, d) R_total (Eq. 30)
    # After predict: the noise-free nominals and Q(dt), where a dropped channel restarts.
    drift: Array | None = None
    process_cov: Array | None = None


def _chol_factor(cov: Array) -> Array:
    try:
        return np.asarray(np.linalg.cholesky(cov), dtype=np.float64)
    except np.linalg.LinAlgError:
        s, v = np.linalg.eigh(cov)
        return np.asarray(v * np.sqrt(np.clip(s, 0.0, None)), dtype=np.float64)


def repair_covariance(cov: Array, floor: float = 1e-12) -> tuple[Array, NDArray[np.bool_]]:
    """Symmetrise ``cov (..., d, d)`` and clip eigenvalues below ``floor * max(trace/d, 1e-300)``.

    Returns the repaired array and a mask ``(...)`` of the matrices that needed it (not PD).
    """
    c = 0.5 * (cov + np.swapaxes(cov, -1, -2))
    s, v = np.linalg.eigh(c)
    scale = np.maximum(np.trace(c, axis1=-2, axis2=-1) / c.shape[-1], 1e-300)[..., None]
    bad = np.any(s <= floor * scale, axis=-1)
    if not np.any(bad):
        return c, bad
    s = np.maximum(s, floor * scale)
    fixed = (v * s[..., None, :]) @ np.swapaxes(v, -1, -2)
    return np.where(bad[..., None, None], fixed, c), bad


def _moment_match(log_psi: Array, est: Array, P: Array) -> tuple[Array, Array, Array]:
    """Normalised channel log-weights and the mixture's ``x_total``, ``R_total`` (Eqs. 28-30)
    of channel estimates ``est (..., C, d)`` with covariances ``P (..., C, d, d)``."""
    top = np.max(log_psi, axis=-1, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    psi = np.exp(log_psi - top)
    total = psi.sum(axis=-1, keepdims=True)
    psi = np.where(total > 0, psi / np.where(total > 0, total, 1.0), 1.0 / psi.shape[-1])
    mean = np.einsum("...c,...cd->...d", psi, est)  # Eq. 28
    dev = est - mean[..., None, :]
    cov = np.einsum("...c,...cij->...ij", psi, P) + np.einsum(
        "...c,...ci,...cj->...ij", psi, dev, dev
    )  # Eq. 30
    return np.log(np.maximum(psi, 1e-300)), mean, cov


class SPPEKFBank:
    """N parallel EKF channels on a random state partition (Zhai 2007, Sec. 3.1.1), a
    :class:`~fusetrack.core.Filter` over :class:`BankState`.

    ``memoryless=True`` (the thesis's experiments) weights channels by their current likelihood
    only (Eq. 29 with equal previous weights).
    """

    def __init__(
        self,
        motion: MotionModel,
        sensors: Sequence[SensorModel],
        n_channels: int = 20,
        *,
        memoryless: bool = True,
        stats: SISStats | None = None,
    ) -> None:
        if isinstance(n_channels, bool) or int(n_channels) != n_channels or n_channels < 1:
            raise ConfigError(invalid("n_channels", n_channels, "an integer >= 1"))
        self.motion = motion
        self.sensors = list(sensors)
        self.n_channels = int(n_channels)
        self.memoryless = memoryless
        self.stats = stats if stats is not None else SISStats()

    def initialize(
        self, prior: Gaussian, rng: np.random.Generator, batch_shape: tuple[int, ...] = ()
    ) -> BankState:
        """Nominals ``~ N(x(0), R(0))``, residual 0 with covariance 0 (Zhai 2007, Eqs. 15-17)."""
        mean, cov = np.asarray(prior.mean, float), np.asarray(prior.cov, float)
        d = len(mean)
        nominal = (
            mean + rng.standard_normal((*batch_shape, self.n_channels, d)) @ _chol_factor(cov).T
        )
        zeros = np.zeros_like(nominal)
        log_psi = np.full((*batch_shape, self.n_channels), -np.log(self.n_channels))
        return BankState(
            nominal,
            zeros,
            np.zeros((*nominal.shape, d)),
            log_psi,
            np.broadcast_to(mean, (*batch_shape, d)).copy(),
            np.broadcast_to(cov, (*batch_shape, d, d)).copy(),
        )

    def predict(
        self, state: BankState, dt: float, rng: np.random.Generator | None = None
    ) -> BankState:
        """Propagate every channel: a noisy nominal (Eq. 18), the residual and its covariance
        through the Jacobian at the old nominal (Eqs. 19, 23, 26)."""
        rng = rng if rng is not None else np.random.default_rng()
        m = self.motion
        q = np.asarray(m.noise_cov(dt), float)
        g = _chol_factor(q)
        x_prev = state.nominal
        w = rng.standard_normal(x_prev.shape) @ g.T
        drift = np.asarray(m.mean(x_prev, dt))
        nominal = drift + w  # Eq. 18
        F = np.asarray(m.jacobian(x_prev, dt))  # Eq. 19
        resid = np.einsum("...ij,...j->...i", F, state.resid) - w  # Eq. 23
        P = F @ state.cov @ np.swapaxes(F, -1, -2) + q  # Eq. 26
        uniform = np.full_like(state.log_psi, -np.log(state.log_psi.shape[-1]))
        log_psi, mean, cov = _moment_match(
            uniform if self.memoryless else state.log_psi, nominal + resid, P
        )
        return BankState(nominal, resid, P, log_psi, mean, cov, drift, q)

    def update(
        self,
        state: BankState,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> BankState:
        """Update every channel with the measurements of the bank's sensors (Eqs. 20-30)."""
        ids = [s.sensor_id for s in self.sensors]
        zs: list[Array | None] = [None] * len(ids)
        for meas in measurements:
            if meas.sensor_id not in ids:
                raise UnknownSensorError(invalid("sensor_id", meas.sensor_id, f"one of {ids}"))
            zs[ids.index(meas.sensor_id)] = meas.value
        return self.update_aligned(state, zs)

    def update_aligned(self, state: BankState, zs: Zs) -> BankState:
        """:meth:`update` with the step's measurements aligned with ``sensors`` (None or
        non-finite: the sensor is silent); the form the PF-SP-PEKF proposals hold."""
        nominal, resid, P = state.nominal, state.resid, state.cov
        loglik = np.zeros(nominal.shape[:-1])
        d = nominal.shape[-1]
        eye = np.eye(d)
        for sensor, z in zip(self.sensors, zs):
            if z is None:
                continue
            za = np.asarray(z, float)
            if za.ndim == 0:
                za = za[None]
            if not np.all(np.isfinite(za)):
                continue
            H = np.asarray(sensor.jacobian(nominal))  # Eq. 22
            R = np.asarray(sensor.noise_cov(nominal))
            innov = sensor.residual(
                np.expand_dims(za, -2), sensor.predict(nominal + resid)
            )  # Eq. 27, as printed
            Ht = np.swapaxes(H, -1, -2)
            S = H @ P @ Ht + R
            S = 0.5 * (S + np.swapaxes(S, -1, -2))
            try:
                Sinv = np.linalg.inv(S)
                logdet = np.linalg.slogdet(S)[1]
            except np.linalg.LinAlgError:
                S, _ = repair_covariance(S)
                Sinv, logdet = np.linalg.inv(S), np.linalg.slogdet(S)[1]
            G = P @ Ht @ Sinv  # Eq. 25
            resid = resid + np.einsum("...ij,...j->...i", G, innov)  # Eq. 24
            A = eye - G @ H
            P = A @ P @ np.swapaxes(A, -1, -2) + G @ R @ np.swapaxes(G, -1, -2)  # Joseph form
            maha = np.einsum("...i,...ij,...j->...", innov, Sinv, innov)
            loglik = loglik - 0.5 * (maha + logdet + za.shape[-1] * _LOG_2PI)
        finite = np.all(np.isfinite(P), axis=(-2, -1)) & np.all(np.isfinite(resid), axis=-1)
        finite &= np.isfinite(loglik)
        if not np.all(finite):  # dropped channels restart at the noise-free prediction
            self.stats.dropped_channels += int(np.sum(~finite))
            restart = state.drift if state.drift is not None else nominal
            q = (
                state.process_cov
                if state.process_cov is not None
                else state.total_cov[..., None, :, :]
            )
            P = np.where(finite[..., None, None], P, q)
            resid = np.where(finite[..., None], resid, 0.0)
            nominal = np.where(finite[..., None], nominal, restart)
            loglik = np.where(finite, loglik, -np.inf)
        P, fixed = repair_covariance(P)
        self.stats.repaired_channels += int(np.sum(fixed))
        log_psi = loglik if self.memoryless else loglik + state.log_psi  # Eq. 29
        log_psi, mean, cov = _moment_match(log_psi, nominal + resid, P)
        return BankState(nominal, resid, P, log_psi, mean, cov)

    def feedback(
        self, state: BankState, estimate: Array, mode: str = "residual", cov: Array | None = None
    ) -> BankState:
        """Re-partition every channel at the particle estimate.

        ``mode="residual"`` (Algorithm 1 as printed): ``x_r = x_PF - x_n``, the nominal keeps its
        own random trajectory. ``"nominal"``: ``x_n = x_PF``, ``x_r = 0`` -- the channels are then
        linearised at the estimate instead of at nominals that drift freely (an option, not the
        thesis's). ``cov`` (optional) replaces the channels' residual covariance.
        """
        est = np.asarray(estimate)[..., None, :]
        new_cov = (
            state.cov
            if cov is None
            else np.broadcast_to(cov[..., None, :, :], state.cov.shape).copy()
        )
        if mode == "nominal":
            nominal = np.broadcast_to(est, state.nominal.shape).copy()
            return BankState(
                nominal, np.zeros_like(nominal), new_cov, state.log_psi, state.mean, state.total_cov
            )
        return BankState(
            state.nominal,
            est - state.nominal,
            new_cov,
            state.log_psi,
            state.mean,
            state.total_cov,
        )


def gaussian_draw(
    mean: Array, cov: Array, n: int, rng: np.random.Generator, jitter: float = 1e-9
) -> tuple[Array, Array]:
    """``n`` draws from ``N(mean, cov)`` per leading index and their log densities.

    ``mean (..., d)``, ``cov (..., d, d)`` -> ``x (..., n, d)``, ``log q (..., n)``. A relative
    ``jitter`` on the diagonal keeps a (nearly) singular covariance usable.
    """
    d = mean.shape[-1]
    L, logdet = _jittered_factor(cov, jitter)
    e = rng.standard_normal((*mean.shape[:-1], n, d))
    x = mean[..., None, :] + np.einsum("...ij,...nj->...ni", L, e)
    log_q = -0.5 * (np.sum(e * e, axis=-1) + logdet[..., None] + d * _LOG_2PI)
    return x, log_q


def gaussian_draw_rows(
    mean: Array, cov: Array, rows: NDArray[np.bool_], rng: np.random.Generator, jitter: float = 1e-9
) -> tuple[Array, Array]:
    """The rows ``rows (..., n)`` of :func:`gaussian_draw` ``(mean, cov, n, rng)``: the same
    normals are drawn (the generator advances as there), only the chosen rows are transformed.

    Returns ``x (M, d)``, ``log q (M,)`` for the ``M`` true entries of ``rows`` in C order (what
    ``array[rows]`` selects), so that a caller drawing each particle from one of several
    Gaussians pays the transform once per particle, not once per Gaussian.
    """
    d = mean.shape[-1]
    L, logdet = _jittered_factor(cov, jitter)
    e = rng.standard_normal((*mean.shape[:-1], rows.shape[-1], d))[rows]
    batch = (*mean.shape[:-1], rows.shape[-1])
    if mean.ndim == 1:  # one Gaussian: no per-row copies of its factor
        x = mean + np.einsum("ij,nj->ni", L, e)
    else:
        Ls = np.broadcast_to(L[..., None, :, :], (*batch, d, d))[rows]
        x = np.broadcast_to(mean[..., None, :], (*batch, d))[rows] + np.einsum("nij,nj->ni", Ls, e)
    ld = np.broadcast_to(logdet[..., None], batch)[rows]
    return x, -0.5 * (np.sum(e * e, axis=-1) + ld + d * _LOG_2PI)


def _jittered_factor(cov: Array, jitter: float) -> tuple[Array, Array]:
    """Cholesky factor of ``cov`` plus a relative ``jitter`` on the diagonal, and its log det."""
    d = cov.shape[-1]
    scale = np.maximum(np.trace(cov, axis1=-2, axis2=-1) / d, 1e-300)
    L = np.linalg.cholesky(cov + (jitter * scale)[..., None, None] * np.eye(d))
    return L, 2.0 * np.sum(np.log(np.diagonal(L, axis1=-2, axis2=-1)), axis=-1)


@dataclass
class SPPEKFProposal:
    """The PF-SP-PEKF proposal (Zhai 2007, Algorithm 1 / Table 1).

    Every particle is drawn from the bank's moment-matched Gaussian ``N(x_total, inflation R_total)``;
    after resampling the bank is re-partitioned at the particle estimate (``feedback=True``,
    essential: without it the bank diverges on the scalar benchmark).
    """

    n_channels: int = 20
    inflation: float = 1.0
    feedback_on: bool = True
    memoryless: bool = True
    repartition: str = "residual"  # "residual" (as printed) or "nominal" (see SPPEKFBank.feedback)

    def initialize(
        self, prior: Gaussian, particles: Array, rng: np.random.Generator
    ) -> BankState | Gaussian:
        """The prior itself: the bank is drawn at the first step (it needs the filter's models),
        after the particles, so the draws keep their order."""
        return prior

    def _bank(self, filt: object) -> SPPEKFBank:
        bank = getattr(self, "_bank_obj", None)
        if bank is None or bank.motion is not filt.motion:  # type: ignore[attr-defined]
            bank = SPPEKFBank(
                filt.motion,  # type: ignore[attr-defined]
                filt.sensors,  # type: ignore[attr-defined]
                self.n_channels,
                memoryless=self.memoryless,
                stats=filt.stats,  # type: ignore[attr-defined]
            )
            self._bank_obj = bank
        return bank

    def draw(
        self,
        state: BankState | Gaussian,
        prev: Array,
        zs: Zs,
        dt: float,
        rng: np.random.Generator,
        filt: object,
    ) -> tuple[Array, Array, BankState]:
        bank = self._bank(filt)
        if isinstance(state, Gaussian):  # the first step: nominals from the prior
            state = bank.initialize(state, rng, prev.shape[:-2])
        state = bank.update_aligned(bank.predict(state, dt, rng), zs)
        x, log_q = gaussian_draw(state.mean, self.inflation * state.total_cov, prev.shape[-2], rng)
        return x, log_q, state

    def feedback(
        self, state: BankState, particles: Array, estimate: Array, filt: object
    ) -> BankState:
        if not self.feedback_on:
            return state
        return self._bank(filt).feedback(state, estimate, self.repartition)
