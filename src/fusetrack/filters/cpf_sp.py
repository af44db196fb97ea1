"""CPF-SP: the centralised multi-sensor particle filter with state partition (Zhai 2007,
Sec. 3.3.4, Algorithm 2 / Table 4, Fig 14).

Every active sensor runs its own SP-PEKF bank (:class:`~fusetrack.filters.sp_pekf.SPPEKFBank`) on
its own measurement (its DOA); the fusion centre moment-matches the banks' Gaussians with the
sensor weights ``W_k`` (received-intensity shares, passed per step as ``aux``; equal weights when
``aux`` is None), ``x_all = sum W_k x_k``, ``R_all = sum W_k [R_k + (x_k - x_all)(.)^T]`` (the
thesis writes the mixture as if it were this Gaussian; spec choice 24), draws the particles from
``N(x_all, R_all)`` and weights them with the product of all active sensors' likelihoods (Eq. 13).
After resampling, the estimate is sent back and every active bank is re-partitioned at it.

A sensor is active at a step when its measurement is finite. A newly active sensor's bank starts
from ``N(x_PF(t-1), Cov_particles(t-1))`` (spec choice); a sensor that goes quiet drops its bank.
With no active sensor the proposal is the transition prior.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.beliefs import Gaussian
from .sis import Array, Zs
from .sp_pekf import BankState, SPPEKFBank, gaussian_draw


@dataclass
class CPFSPState:
    banks: dict[int, BankState] = field(default_factory=dict)
    mean: Array | None = None
    cov: Array | None = None


@dataclass
class CPFSPProposal:
    """Fusion-centre proposal of CPF-SP (Algorithm 2). ``aux`` per step: weights ``(K,)``."""

    n_channels: int = 10
    feedback_cov: str = (
        "keep"  # "keep" (spec choice 10) or "particles" (channels take the particle cov)
    )
    repartition: str = "residual"  # "residual" (as printed) or "nominal" (see SPPEKFBank.feedback)

    def initialize(self, prior: Gaussian, particles: Array, rng: np.random.Generator) -> CPFSPState:
        return CPFSPState({}, np.asarray(prior.mean, float), np.asarray(prior.cov, float))

    def draw(
        self, state: CPFSPState, prev: Array, zs: Zs, dt: float, rng: np.random.Generator, filt: Any
    ) -> tuple[Array, Array | None, CPFSPState]:
        active = [
            k
            for k, z in enumerate(zs)
            if z is not None and np.all(np.isfinite(np.asarray(z, float)))
        ]
        banks: dict[int, BankState] = {}
        if not active:
            return filt.motion.sample(prev, dt, rng), None, CPFSPState({}, state.mean, state.cov)
        weights = np.ones(len(zs)) if filt.aux is None else np.asarray(filt.aux, float)
        means, covs, w = [], [], []
        for k in active:
            bank = SPPEKFBank(filt.motion, [filt.sensors[k]], self.n_channels, stats=filt.stats)
            bs = state.banks.get(k)
            if bs is None:  # newly active: start from the last particle estimate
                assert state.mean is not None and state.cov is not None
                bs = bank.initialize(Gaussian(state.mean, state.cov), rng, prev.shape[:-2])
            bs = bank.step(bs, [zs[k]], dt, rng)
            banks[k] = bs
            means.append(bs.mean)
            covs.append(bs.total_cov)
            w.append(weights[k])
        wa = np.asarray(w, float)
        wa = wa / wa.sum() if wa.sum() > 0 else np.full(len(w), 1.0 / len(w))
        M, C = np.array(means), np.array(covs)
        mean = np.einsum("k,k...d->...d", wa, M)
        dev = M - mean
        cov = np.einsum("k,k...ij->...ij", wa, C) + np.einsum("k,k...i,k...j->...ij", wa, dev, dev)
        x, log_q = gaussian_draw(mean, cov, prev.shape[-2], rng)
        return x, log_q, CPFSPState(banks, state.mean, state.cov)

    def feedback(
        self, state: CPFSPState, particles: Array, estimate: Array, filt: Any
    ) -> CPFSPState:
        dev = particles - estimate[..., None, :]
        cov = np.einsum("...ni,...nj->...ij", dev, dev) / max(particles.shape[-2] - 1, 1)
        bank = SPPEKFBank(filt.motion, [], self.n_channels)
        keep = self.feedback_cov == "keep"
        banks = {
            k: bank.feedback(b, estimate, self.repartition, None if keep else cov)
            for k, b in state.banks.items()
        }
        return CPFSPState(banks, np.asarray(estimate), cov + 1e-9 * np.eye(cov.shape[-1]))
