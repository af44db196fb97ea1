"""What no synchronisation can beat on Kushwaha 2010's simulated network (issue 19, item 3): the
Cramér-Rao bound of a packet's translated timestamp, beside the residual table of
``kushwaha2010-timesync``.

**A clock map.** RBS (and the gateway's serial pairs) fit a line ``y = α + β x`` between two
clocks from ``K`` common events, each stamped by both with white Gaussian jitter
(``s_x,k = x_k + u_k``, ``s_y,k = α + β x_k + v_k``). The events' true readings ``x_k`` are
unknown (RBS trusts no sender clock), so they are nuisance parameters; taking them out of the
joint information (Schur complement, Kay 1993, Vol. I, Eq. 3.13) leaves

    J(α, β) = X^T X / (σ_y² + β² σ_x²),   X = [1, x_k]   (:func:`map_information`),

the errors-in-variables line's information, and the map's value at a query ``x*`` has variance
at least ``g^T J^{-1} g``, ``g = [1, x*]`` (:func:`map_value_variance`). With exact ``x_k``
(``σ_x = 0``) this is the least-squares line's prediction variance, which least squares attains.

**A packet's timestamp.** A video frame's stamp goes through RBS only; an acoustic packet's
through the hop-by-hop elapsed-time translation (one jitter per hop and one at the gateway mote:
``(hops + 1) σ_hop²``, :func:`hop_variance`), the gateway's mote → PC map and RBS. The three
stages use independent data, so the bound of the composed stamp is the sum of each stage's
variance carried through the later maps' slopes (:func:`chained_variance`). The skews' effect on
the measured residence times (``ρ × residence``, under 1 µs per hop) is left out: a genie knowing
the skews removes it, so the bound stays below.

**What it bounds.** The beacons' true emission times are treated as unknown, as RBS does (the
simulation happens to send them on an exact 1 s grid; an estimator told so could do better).
Two bounds per packet: with the beacons of the protocol's window (the 8 before the stamp: what
the protocol's least squares sees and attains) and with every beacon received before the stamp
(what any causal estimator on the simulation's drift-free clocks cannot beat).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...core import ConfigError, invalid

Array = NDArray[np.float64]


def map_information(x: ArrayLike, beta: float, var_x: float, var_y: float) -> Array:
    """Fisher information ``(2, 2)`` of ``(α, β)`` from ``K`` events read by both clocks
    (true readings ``x`` ``(K,)`` of the first clock, unknown; jitter variances ``var_x``,
    ``var_y``): ``X^T X / (var_y + β² var_x)``."""
    xs = np.asarray(x, dtype=float)
    if xs.ndim != 1 or xs.size < 2:
        raise ConfigError(invalid("x", xs.shape, "at least 2 common events"))
    total = var_y + beta**2 * var_x
    if not total > 0:
        raise ConfigError(invalid("var_x, var_y", (var_x, var_y), "jitter variances, not both 0"))
    X = np.column_stack([np.ones_like(xs), xs])
    return np.asarray(X.T @ X / total)


def map_value_variance(
    x: ArrayLike, beta: float, var_x: float, var_y: float, query: float
) -> float:
    """CRLB of ``α + β x*`` at ``query = x*`` (s²), from :func:`map_information`. The query is
    centred on the events' mean first, so ``J`` is well conditioned for clock readings of 10⁹ s."""
    xs = np.asarray(x, dtype=float)
    centre = float(xs.mean())
    J = map_information(xs - centre, beta, var_x, var_y)
    g = np.array([1.0, query - centre])
    return float(g @ np.linalg.solve(J, g))


def hop_variance(hops: int, jitter: float) -> float:
    """Variance (s²) of an event's time carried over ``hops`` mote hops by elapsed-time
    translation: one timestamping jitter per hop and one on arrival (:class:`~fusetrack.world.
    clocks.HopTranslation`)."""
    if hops < 1:
        raise ConfigError(invalid("hops", hops, ">= 1"))
    return (hops + 1) * jitter**2


def chained_variance(stages: Sequence[tuple[float, float]]) -> float:
    """Variance of a timestamp passed through maps in turn: ``stages`` ``[(variance added,
    slope of the map applied after it), ...]``, first stage first; the variance so far is
    scaled by each later slope squared (independent stages: their variances add)."""
    total = 0.0
    for added, slope in stages:
        total = (total + added) * slope**2
    return total


__all__ = ["chained_variance", "hop_variance", "map_information", "map_value_variance"]
