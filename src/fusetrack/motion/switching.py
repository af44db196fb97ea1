"""A set of motion models switched by a Markov chain (jump Markov / multiple-model dynamics).

Bar-Shalom, Li & Kirubarajan 2001, Ch. 11 (multiple-model approach): the mode ``r_k`` follows a
Markov chain with ``P(r_k = j | r_{k-1} = i) = transition[i, j]``; given the mode, the state moves
by that model.
The chain advances once per call of :meth:`MarkovSwitching.sample_modes` (per step, whatever
``dt`` is).

Shared state: the set works on the state of its largest model (``dim = max(model.dim)``). A
smaller model acts on the leading ``model.dim`` components and carries the rest unchanged and
noise-free, so its layout must be a prefix of the largest one: the models must agree on
``position_index`` and (where both have one) ``velocity_index``. Example: ``ConstantVelocity(2)``
with ``CoordinatedTurnRate()`` share ``[x, y, vx, vy, omega]``; in the CV mode the turn rate is
frozen. Because the carried components get no noise, such a mode's ``noise_cov`` is singular and
its ``log_density`` is ``-inf`` when they change.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, MotionModel, ShapeError, invalid
from ._common import _SUPPORT_RTOL, Array, as_state, check_dt, check_rng

IntArray = NDArray[np.intp]


@dataclass(frozen=True, eq=False)
class MarkovSwitching:
    """Motion models switched by a Markov chain with row-stochastic ``transition`` ``(M, M)``.

    Every method takes the per-row mode as an extra ``modes`` integer array that broadcasts
    against the leading axes of ``x``; outputs have the broadcast leading shape. ``transition``
    (any array-like) is stored as a read-only float array with its rows renormalised.

    >>> from fusetrack.motion import ConstantVelocity, CoordinatedTurnRate
    >>> models = (ConstantVelocity(2), CoordinatedTurnRate())
    >>> imm = MarkovSwitching(models, [[0.95, 0.05], [0.1, 0.9]])
    >>> imm.dim
    5
    """

    models: tuple[MotionModel, ...]
    transition: ArrayLike
    dim: int = field(init=False, repr=False)
    position_index: tuple[int, ...] = field(init=False, repr=False)
    velocity_index: tuple[int, ...] | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        models = tuple(self.models) if isinstance(self.models, Sequence) else ()
        if not models:
            raise ConfigError(
                invalid("models", self.models, "a non-empty sequence of motion models")
            )
        for i, m in enumerate(models):
            if not isinstance(m, MotionModel):
                raise ConfigError(
                    invalid(f"models[{i}]", m, "a motion model (dim, mean, sample, jacobian, ...)")
                )
        n = len(models)
        t = np.array(self.transition, dtype=float)
        if t.shape != (n, n):
            raise ShapeError(invalid("transition.shape", t.shape, f"({n}, {n}) for {n} models"))
        if not np.all(np.isfinite(t)) or np.any(t < 0):
            raise ConfigError(invalid("transition", t.tolist(), "finite entries >= 0"))
        rows = t.sum(axis=1)
        bad = np.flatnonzero(np.abs(rows - 1.0) > 1e-8)
        if bad.size:
            i = int(bad[0])
            raise ConfigError(invalid(f"transition[{i}]", t[i].tolist(), "a row that sums to 1"))
        t = t / rows[:, None]
        t.setflags(write=False)
        big = max(models, key=lambda m: m.dim)
        pos = getattr(big, "position_index", None)
        vel = getattr(big, "velocity_index", None)
        for i, m in enumerate(models):
            if getattr(m, "position_index", None) != pos:
                raise ConfigError(
                    invalid(
                        f"models[{i}].position_index",
                        getattr(m, "position_index", None),
                        f"{pos}, as in the largest model (the models must share a layout)",
                    )
                )
            v = getattr(m, "velocity_index", None)
            if v is not None and v != vel:
                raise ConfigError(
                    invalid(
                        f"models[{i}].velocity_index",
                        v,
                        f"{vel}, as in the largest model (the models must share a layout)",
                    )
                )
        object.__setattr__(self, "models", models)
        object.__setattr__(self, "transition", t)
        object.__setattr__(self, "dim", int(big.dim))
        object.__setattr__(self, "position_index", pos)
        object.__setattr__(self, "velocity_index", vel)

    @property
    def n_modes(self) -> int:
        """Number of models ``M``."""
        return len(self.models)

    @property
    def state_names(self) -> tuple[str, ...]:
        """Component names of the shared state (those of the largest model)."""
        big = max(self.models, key=lambda m: m.dim)
        names = getattr(big, "state_names", None)
        return tuple(names) if names is not None else tuple(f"x{i}" for i in range(self.dim))

    # ----------------------------------------------------------------------------- modes

    def _check_modes(self, modes: ArrayLike) -> IntArray:
        a = np.asarray(modes)
        if a.dtype.kind not in "iu":
            raise ConfigError(
                invalid("modes", modes, f"an integer array with values in 0..{self.n_modes - 1}")
            )
        if a.size and (a.min() < 0 or a.max() >= self.n_modes):
            raise ConfigError(invalid("modes", modes, f"integers in 0..{self.n_modes - 1}"))
        return a.astype(np.intp, copy=False)

    def sample_modes(self, modes: ArrayLike, rng: np.random.Generator) -> IntArray:
        """Next mode of each element of ``modes``: a draw from ``transition[modes]``; same shape."""
        m = self._check_modes(modes)
        check_rng(rng)
        cum = np.cumsum(self.transition, axis=1)
        cum[:, -1] = 1.0
        u = rng.random(m.shape)
        nxt = np.sum(cum[m] <= u[..., None], axis=-1)  # inverse CDF of row transition[mode]
        return np.minimum(nxt, self.n_modes - 1).astype(np.intp)

    # ----------------------------------------------------------------------------- helpers

    def _flat(
        self, modes: ArrayLike, states: dict[str, ArrayLike]
    ) -> tuple[tuple[int, ...], IntArray, list[Array]]:
        """Broadcast ``modes`` and the states' leading axes; return lead shape and flat arrays."""
        m = self._check_modes(modes)
        arrs = [as_state(s, self.dim, self.state_names, field=f) for f, s in states.items()]
        try:
            lead = np.broadcast_shapes(m.shape, *(a.shape[:-1] for a in arrs))
        except ValueError:
            shown = {f: a.shape for f, a in zip(states, arrs)}
            raise ShapeError(
                invalid(
                    "modes.shape",
                    m.shape,
                    f"a shape that broadcasts with the leading axes of {shown}",
                )
            ) from None
        n = int(np.prod(lead, dtype=np.int64))
        flat = [np.broadcast_to(a, (*lead, self.dim)).reshape(n, self.dim) for a in arrs]
        return lead, np.broadcast_to(m, lead).reshape(n), flat

    def _groups(self, modes: IntArray) -> list[tuple[int, Any, IntArray]]:
        return [
            (i, mdl, idx)
            for i, mdl in enumerate(self.models)
            if (idx := np.flatnonzero(modes == i)).size
        ]

    # ----------------------------------------------------------------------------- model API

    def mean(self, x: ArrayLike, dt: float, modes: ArrayLike) -> Array:
        """``f_{mode}(x, dt)`` row by row; ``(*lead, dim)``."""
        dt = check_dt(dt)
        lead, m, (xf,) = self._flat(modes, {"x": x})
        out = xf.copy()
        for _, mdl, idx in self._groups(m):
            d = mdl.dim
            out[idx, :d] = mdl.mean(xf[idx, :d], dt)
        return out.reshape(*lead, self.dim)

    def sample(self, x: ArrayLike, dt: float, rng: np.random.Generator, modes: ArrayLike) -> Array:
        """A draw of the next state of every row under its mode; ``(*lead, dim)``.

        Draws model by model in the order of ``models`` (reproducible for a given seed).
        """
        dt = check_dt(dt)
        check_rng(rng)
        lead, m, (xf,) = self._flat(modes, {"x": x})
        out = xf.copy()
        for _, mdl, idx in self._groups(m):
            d = mdl.dim
            out[idx, :d] = mdl.sample(xf[idx, :d], dt, rng)
        return out.reshape(*lead, self.dim)

    def jacobian(self, x: ArrayLike, dt: float, modes: ArrayLike) -> Array:
        """``df_{mode}/dx`` row by row (identity on carried components); ``(*lead, dim, dim)``."""
        dt = check_dt(dt)
        lead, m, (xf,) = self._flat(modes, {"x": x})
        out = np.zeros((m.size, self.dim, self.dim))
        out[:] = np.eye(self.dim)
        for _, mdl, idx in self._groups(m):
            d = mdl.dim
            out[idx, :d, :d] = mdl.jacobian(xf[idx, :d], dt)
        return out.reshape(*lead, self.dim, self.dim)

    def noise_cov(self, dt: float, modes: ArrayLike | None = None) -> Array:
        """``Q_{mode}(dt)`` padded with zeros to ``(dim, dim)``: ``(*modes.shape, dim, dim)``;
        with ``modes=None`` every model's, ``(M, dim, dim)``."""
        dt = check_dt(dt)
        m = np.arange(self.n_modes) if modes is None else self._check_modes(modes)
        per = np.zeros((self.n_modes, self.dim, self.dim))
        for i, mdl in enumerate(self.models):
            per[i, : mdl.dim, : mdl.dim] = mdl.noise_cov(dt)
        return per[m]

    def log_density(self, x_next: ArrayLike, x: ArrayLike, dt: float, modes: ArrayLike) -> Array:
        """``log p(x_next | x, mode)`` row by row; ``(*lead)``.

        Each model's own density on its components; ``-inf`` where a carried component changed.
        """
        dt = check_dt(dt)
        lead, m, (xn, xf) = self._flat(modes, {"x_next": x_next, "x": x})
        out = np.empty(m.size)
        for _, mdl, idx in self._groups(m):
            d = mdl.dim
            ld = np.asarray(mdl.log_density(xn[idx, :d], xf[idx, :d], dt), dtype=float)
            if d < self.dim:
                a, b = xn[idx, d:], xf[idx, d:]
                tol = _SUPPORT_RTOL * np.maximum(np.abs(a), np.abs(b))
                ld = np.where(np.all(np.abs(a - b) <= tol, axis=-1), ld, -np.inf)
            out[idx] = ld
        return out.reshape(lead)
