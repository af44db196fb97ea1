"""The tracker interface every tracker in :mod:`fusetrack.tracking` follows, and the summary of
a track's belief."""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..core import Measurement


@dataclass(frozen=True)
class TrackView:
    """A track as every tracker's state shows it: its id and belief."""

    id: int
    belief: Any


@runtime_checkable
class Tracker(Protocol):
    """What every tracker offers (single target, multi-target, GM-PHD, MCMCDA): pure
    ``initial_state()`` and ``step(state, time, measurements, rng, scanned=None) -> state``,
    whose ``state.confirmed`` are :class:`TrackView`-like tracks (``id``, ``belief``);
    ``filter`` is the per-track filter (None when there is none)."""

    filter: Any

    def initial_state(self) -> Any: ...

    def step(
        self,
        state: Any,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
        *,
        scanned: Collection[str] | None = None,
    ) -> Any: ...


def belief_summary(filt: Any, belief: Any) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance of a belief: the filter's ``estimate`` when it has one."""
    estimate = getattr(filt, "estimate", None)
    s = estimate(belief) if callable(estimate) else belief
    return np.asarray(s.mean), np.asarray(s.cov)
