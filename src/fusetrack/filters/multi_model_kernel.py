"""The fused Numba step of :class:`~fusetrack.filters.multi_model_pf.MultiModelBearingPF`
(Lee 2009, Eqs. 3.3-3.6 and the consistent estimator) for the usual bank of 2-D turn models.

:func:`predict_weigh_kernel` predicts every particle with every model, weights it against every
(unlabelled) bearing and forms the estimate in one pass over a batch ``(B, O)`` of filters, with
the same arithmetic and the same random draws as the NumPy reference
(:meth:`MultiModelBearingPF.update` of :meth:`MultiModelBearingPF.predict`);
:meth:`MultiModelBearingPF.step` runs it for one filter, the periodic batch of Lee 2009's camera
cooperation for many.
"""

from __future__ import annotations

import numba
import numpy as np

Array = np.ndarray


@numba.njit(cache=True, nogil=True)
def predict_weigh_kernel(
    parts: Array,
    eta: Array,
    sigma_a: float,
    alphas: Array,
    dt: float,
    sensor: Array,
    z: Array,
    inv_var: float,
    pred: Array,
    w_ml: Array,
    est: Array,
) -> int:  # pragma: no cover - jit
    """Fused :meth:`MultiModelBearingPF.propagate_every_model` + weights + consistent estimate for a batch.

    ``parts (B, O, L, 4)``, ``eta (J, B, O, L, 2)`` (standard normal draws, scaled here by
    ``sigma_a``: the same product as the reference's), ``z (B, N)``; writes
    ``pred (B, O, J, L, 4)``, normalised ``w_ml (B, O, J, L)`` and ``est (B, O, 4)``; returns the
    number of degenerate filters (equal weights then). Same arithmetic as the NumPy reference.
    """
    B, O, L = parts.shape[0], parts.shape[1], parts.shape[2]
    J, N = alphas.shape[0], z.shape[1]
    two_pi = 2.0 * np.pi
    r2 = np.empty((J, L, N))
    twin = np.full(J, -1)  # a model with the opposite turn: sin flips, cos and a1 are shared
    for j in range(J):
        for i in range(j):
            if alphas[i] == -alphas[j] and alphas[j] != 0.0:
                twin[j] = i
    sw, cw = np.empty(J), np.empty(J)
    degenerate = 0
    for b in range(B):
        for o in range(O):
            top = -np.inf
            for l in range(L):
                x, y = parts[b, o, l, 0], parts[b, o, l, 1]
                vx, vy = parts[b, o, l, 2], parts[b, o, l, 3]
                speed = np.hypot(vx, vy)
                for j in range(J):
                    omega = alphas[j] / max(speed, 1e-9) if speed > 1e-9 else 0.0
                    wt = omega * dt
                    if wt == 0.0:  # sin(+-0) = +-0 and cos(+-0) = 1 exactly: no call
                        s_, c_, a1, a2 = wt, 1.0, dt, 0.0
                    elif abs(wt) < 1e-9:
                        s_, c_, a1, a2 = np.sin(wt), np.cos(wt), dt, 0.0
                    else:
                        if twin[j] >= 0:  # sin(-x) = -sin(x), cos(-x) = cos(x) exactly
                            s_, c_ = -sw[twin[j]], cw[twin[j]]
                        else:
                            s_, c_ = np.sin(wt), np.cos(wt)
                        a1, a2 = s_ / omega, (1.0 - c_) / omega
                    sw[j], cw[j] = s_, c_
                    e0, e1 = sigma_a * eta[j, b, o, l, 0], sigma_a * eta[j, b, o, l, 1]
                    px = x + a1 * vx - a2 * vy + 0.5 * dt * dt * e0
                    py = y + a2 * vx + a1 * vy + 0.5 * dt * dt * e1
                    pred[b, o, j, l, 0] = px
                    pred[b, o, j, l, 1] = py
                    pred[b, o, j, l, 2] = c_ * vx - s_ * vy + dt * e0
                    pred[b, o, j, l, 3] = s_ * vx + c_ * vy + dt * e1
                    h = np.arctan2(py - sensor[1], px - sensor[0])
                    for n in range(N):
                        r = h - z[b, n]  # both in [-pi, pi]: one correction wraps it
                        if r >= np.pi:
                            r -= two_pi
                        elif r < -np.pi:
                            r += two_pi
                        v = -0.5 * inv_var * r * r
                        r2[j, l, n] = v
                        if v > top:
                            top = v
            total = 0.0
            for j in range(J):
                for l in range(L):
                    acc = 0.0
                    for n in range(N):
                        d = r2[j, l, n] - top
                        if d > -60.0:  # e^-60 < 1e-26: below rounding of the sum
                            acc += np.exp(d)
                    w_ml[b, o, j, l] = acc
                    total += acc
            if not (np.isfinite(top) and total > 0.0):
                degenerate += 1
                for j in range(J):
                    for l in range(L):
                        w_ml[b, o, j, l] = 1.0 / (J * L)
            else:
                for j in range(J):
                    for l in range(L):
                        w_ml[b, o, j, l] /= total
            for d in range(4):
                acc = 0.0
                for j in range(J):
                    for l in range(L):
                        acc += w_ml[b, o, j, l] * pred[b, o, j, l, d]
                est[b, o, d] = acc
    return degenerate


@numba.njit(cache=True, nogil=True)
def gather_particles(pred: Array, idx: Array) -> Array:  # pragma: no cover - jit
    """``out[b, o, l] = pred[b, o].reshape(J * L, -1)[idx[b, o, l]]``: the resampled particles of
    a batch (``np.take_along_axis`` over the flattened models, without its index arrays);
    ``pred (B, O, J, L, D)``, ``idx (B, O, M)`` -> ``(B, O, M, D)``."""
    B, O, L, D = pred.shape[0], pred.shape[1], pred.shape[3], pred.shape[4]
    M = idx.shape[2]
    out = np.empty((B, O, M, D))
    for b in range(B):
        for o in range(O):
            for m in range(M):
                i = idx[b, o, m]
                j, l = i // L, i % L
                for d in range(D):
                    out[b, o, m, d] = pred[b, o, j, l, d]
    return out


def kernel_bank(models: tuple) -> Array | None:
    """The models' turn accelerations if the kernel implements the bank (2-D turns driven by
    ``alpha``, one ``sigma_a``), else None."""
    fast = all(
        m.ndim == 2 and not np.any(m.accel) and m.turn_axes in (None, (0, 1))
        and m.sigma_a == models[0].sigma_a
        for m in models
    )  # fmt: skip
    return np.array([m.turn_alpha if m.turn_axes else 0.0 for m in models]) if fast else None
