"""CPF-SP: the centralised multi-sensor particle filter with state partition (Zhai 2007,
Sec. 3.3.4, Algorithm 2 / Table 4, Fig 14).

Every active sensor runs its own SP-PEKF bank (:class:`~fusetrack.filters.sp_pekf.SPPEKFBank`) on
its own measurement (its DOA); the fusion centre moment-matches the banks' Gaussians with the
sensor weights ``W_k`` (received-intensity shares, a side input of each step; equal weights when
absent), ``x_all = sum W_k x_k``, ``R_all = sum W_k [R_k + (x_k - x_all)(.)^T]`` (the
thesis writes the mixture as if it were this Gaussian; spec choice 24), draws the particles from
``N(x_all, R_all)`` and weights them with the product of all active sensors' likelihoods (Eq. 13).
After resampling, the estimate is sent back and every active bank is re-partitioned at it.

A sensor is active at a step when its measurement is finite. A newly active sensor's bank starts
from ``N(x_PF(t-1), Cov_particles(t-1))`` (spec choice); a sensor that goes quiet drops its bank.
With no active sensor the proposal is the transition prior.

Speed: when the sensors are translated copies of one another (same type and parameters, other
positions, e.g. a grid of DOA sensors) and the motion model commutes with translations (CV, CA,
coordinated turns), the active banks run as one batched bank (:func:`step_translated`): each
bank works in coordinates centred on its own sensor, so one sensor model serves them all. This
gives the same numbers as the loop over sensors with one NumPy call per step instead of K.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from ..core import Gaussian
from .proposals import Array, Zs
from .sp_pekf import BankState, SPPEKFBank, gaussian_draw


def translated_copies(sensors: list[Any]) -> Array | None:
    """Positions ``(K, k)`` when every sensor is the first one moved elsewhere, else None.

    "Moved" means: same type, same values in every dataclass field except ``sensor_id`` and
    ``position``.
    """
    if not sensors or any(type(s) is not type(sensors[0]) for s in sensors):
        return None
    try:
        names = [
            f.name for f in fields(sensors[0]) if f.init and f.name not in ("sensor_id", "position")
        ]
    except TypeError:
        return None
    first = sensors[0]
    for s in sensors[1:]:
        for n in names:
            a, b = getattr(first, n), getattr(s, n)
            if not np.array_equal(np.asarray(a), np.asarray(b)):
                return None
    return np.array([np.asarray(s.position, dtype=np.float64) for s in sensors])


def commutes_with_translation(motion: Any, shift: Array) -> bool:
    """``f(x + s) = f(x) + s`` and ``F(x + s) = F(x)`` for a position shift ``s`` (checked on two
    random states)."""
    d = int(motion.dim)
    x = np.random.default_rng(0).normal(size=(2, d)) + 1.0
    s = np.zeros(d)
    s[list(motion.position_index)] = shift
    return bool(
        np.allclose(motion.mean(x + s, 1.0) - s, motion.mean(x, 1.0), rtol=1e-9, atol=1e-9)
        and np.allclose(motion.jacobian(x + s, 1.0), motion.jacobian(x, 1.0), atol=1e-9)
    )


def step_translated(
    bank: SPPEKFBank,
    states: list[BankState],
    shifts: Array,
    zs: list[Array],
    dt: float,
    rng: np.random.Generator,
) -> list[BankState]:
    """Step K banks of sensor copies at once: bank ``i`` is moved by ``-shifts[i]`` (``(K, d)``, the
    sensor's offset from ``bank``'s one sensor, in state coordinates), stepped as one batch, and
    moved back. Equals the K separate steps (same draws, in the same order)."""
    sh = [np.reshape(v, (1,) * (st.nominal.ndim - 1) + v.shape) for v, st in zip(shifts, states)]
    shm = [np.reshape(v, (1,) * (st.mean.ndim - 1) + v.shape) for v, st in zip(shifts, states)]
    stacked = BankState(
        np.stack([st.nominal - v for st, v in zip(states, sh)]),
        np.stack([st.resid for st in states]),
        np.stack([st.cov for st in states]),
        np.stack([st.log_psi for st in states]),
        np.stack([st.mean - v for st, v in zip(states, shm)]),
        np.stack([st.total_cov for st in states]),
    )
    z = np.stack([np.asarray(zk, float).reshape(np.shape(zk) or (1,)) for zk in zs])
    out = bank.update_aligned(bank.predict(stacked, dt, rng), [z])
    return [
        BankState(
            out.nominal[i] + sh[i],
            out.resid[i],
            out.cov[i],
            out.log_psi[i],
            out.mean[i] + shm[i],
            out.total_cov[i],
        )
        for i in range(len(states))
    ]


@dataclass(frozen=True)
class CPFSPState:
    """The fusion centre's state, kept in the belief: each active sensor's bank, and the last
    particle mean and covariance (where a newly active sensor's bank starts)."""

    banks: dict[int, BankState] = field(default_factory=dict)
    mean: Array | None = None
    cov: Array | None = None


@dataclass
class CPFSPProposal:
    """Fusion-centre proposal of CPF-SP (Algorithm 2). The sensor weights ``W_k`` ``(K,)``
    arrive each step as a measurement from ``weights_id`` (a side input: the received-intensity
    shares; equal weights when it is absent)."""

    n_channels: int = 10
    feedback_cov: str = (
        "keep"  # "keep" (spec choice 10) or "particles" (channels take the particle cov)
    )
    repartition: str = "residual"  # "residual" (as printed) or "nominal" (see SPPEKFBank.feedback)
    batch_sensors: bool = True  # one batched bank step for translated sensor copies (same numbers)
    weights_id: str = "sensor-weights"

    @property
    def side_inputs(self) -> tuple[str, ...]:
        return (self.weights_id,)

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
        if not active:
            return filt.motion.sample(prev, dt, rng), None, CPFSPState({}, state.mean, state.cov)
        given = filt.side.get(self.weights_id)
        weights = np.ones(len(zs)) if given is None else np.asarray(given, float)
        states = []
        for k in active:
            bs = state.banks.get(k)
            if bs is None:  # newly active: start from the last particle estimate
                assert state.mean is not None and state.cov is not None
                bank = SPPEKFBank(filt.motion, [filt.sensors[k]], self.n_channels, stats=filt.stats)
                bs = bank.initialize(Gaussian(state.mean, state.cov), rng, prev.shape[:-2])
            states.append(bs)
        plan = self._translation_plan(filt)
        if plan is not None:
            origin_bank, shifts = plan
            stepped = step_translated(
                origin_bank, states, shifts[active], [np.asarray(zs[k]) for k in active], dt, rng
            )
        else:
            stepped = []
            for k, bs in zip(active, states):
                bank = SPPEKFBank(filt.motion, [filt.sensors[k]], self.n_channels, stats=filt.stats)
                stepped.append(bank.update_aligned(bank.predict(bs, dt, rng), [zs[k]]))
        banks = dict(zip(active, stepped))
        means = [bs.mean for bs in stepped]
        covs = [bs.total_cov for bs in stepped]
        w = [weights[k] for k in active]
        wa = np.asarray(w, float)
        wa = wa / wa.sum() if wa.sum() > 0 else np.full(len(w), 1.0 / len(w))
        M, C = np.array(means), np.array(covs)
        mean = np.einsum("k,k...d->...d", wa, M)
        dev = M - mean
        cov = np.einsum("k,k...ij->...ij", wa, C) + np.einsum("k,k...i,k...j->...ij", wa, dev, dev)
        x, log_q = gaussian_draw(mean, cov, prev.shape[-2], rng)
        return x, log_q, CPFSPState(banks, state.mean, state.cov)

    def _translation_plan(self, filt: Any) -> tuple[SPPEKFBank, Array] | None:
        """``(bank of one sensor at the origin, state shifts (K, d))`` when the sensors are
        translated copies and the motion commutes with translations (cached per filter)."""
        key = (id(filt.motion), len(filt.sensors), id(filt.stats))
        cached = getattr(self, "_plan", None)
        if cached is not None and cached[0] == key:
            return cached[1]
        plan = None
        positions = translated_copies(filt.sensors) if self.batch_sensors else None
        idx = list(getattr(filt.motion, "position_index", ()) or ())
        if positions is not None and positions.shape[1] == len(idx):
            spread = positions - positions[0]
            if commutes_with_translation(filt.motion, np.abs(spread).max(axis=0) + 1.0):
                origin = replace(filt.sensors[0], position=np.zeros(positions.shape[1]))
                shifts = np.zeros((len(positions), int(filt.motion.dim)))
                shifts[:, idx] = positions
                plan = (
                    SPPEKFBank(filt.motion, [origin], self.n_channels, stats=filt.stats),
                    shifts,
                )
        self._plan = (key, plan)
        return plan

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
