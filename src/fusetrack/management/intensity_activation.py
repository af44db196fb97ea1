"""Power-aware sensor activation by received intensity (Zhai 2007, Sec. 3.3, Table 4).

A sensor wakes up (reports its DOA and runs its local SP-PEKF bank) when the sound level it
receives is at least a fraction ``threshold`` of the source level, on the decibel scale (spec
choice 23: "72/75/78 % of the source intensity" read as ``L >= threshold * source_db``; on the
linear scale the thresholds would need d < 1.2 m). The fusion centre weights the active sensors by
their share of the received intensity, ``W_k = P_k / sum P`` (Table 4), with ``P = 10^(L/10)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, invalid


def active_sensors(levels_db: ArrayLike, threshold: float, source_db: float) -> NDArray[np.bool_]:
    """Which sensors are active: ``L_k >= threshold * source_db`` (NaN levels are inactive)."""
    if not 0.0 < threshold <= 1.0:
        raise ConfigError(invalid("threshold", threshold, "a fraction in (0, 1]"))
    lv = np.asarray(levels_db, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.asarray(np.isfinite(lv) & (lv >= threshold * source_db))


def activation_radius(threshold: float, source_db: float, alpha: float = 2.0) -> float:
    """The noise-free activation distance: ``source_db - 5 alpha log10 d = threshold source_db``."""
    return float(10.0 ** ((1.0 - threshold) * source_db / (5.0 * alpha)))


def intensity_weights(levels_db: ArrayLike, active: ArrayLike) -> NDArray[np.float64]:
    """``W_k = P_k / sum_active P`` with ``P = 10^(L/10)``; zero for inactive sensors."""
    lv = np.asarray(levels_db, dtype=float)
    act = np.asarray(active, dtype=bool)
    if not np.any(act):
        return np.zeros(lv.shape)
    p = np.where(act, 10.0 ** ((lv - np.nanmax(np.where(act, lv, -np.inf))) / 10.0), 0.0)
    return np.asarray(p / p.sum(), dtype=np.float64)
