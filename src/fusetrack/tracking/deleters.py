"""Track deletion: after every scan each confirmed track is offered to the deleter, whose
``should_delete(track)`` says whether it ends there. (Tentative tracks are the initiator's.)

* :class:`MissedCountDeleter` -- ``max_misses`` missed scans in a row (Blackman & Popoli 1999,
  Sec. 3.2.3: the "N consecutive misses" rule);
* :class:`CovarianceDeleter` -- the trace of the covariance (of some components) grew above
  ``max_trace`` (Stone Soup's ``CovarianceBasedDeleter``);
* :class:`ExistenceDeleter` -- the existence probability (:mod:`.existence`, IPDA) fell below
  ``threshold``;
* :class:`AnyOf` -- any of several.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ..core import ConfigError, check_positive, check_probability, invalid
from .state import LiveTrack


@runtime_checkable
class Deleter(Protocol):
    """Decides after a scan whether a confirmed track ends."""

    def should_delete(self, track: LiveTrack) -> bool: ...


@dataclass(frozen=True)
class MissedCountDeleter:
    """Delete a track at its ``max_misses``-th missed scan in a row."""

    max_misses: int

    def __post_init__(self) -> None:
        m = self.max_misses
        if isinstance(m, bool) or not isinstance(m, int | np.integer) or m < 1:
            raise ConfigError(invalid("max_misses", m, "an integer >= 1"))

    def should_delete(self, track: LiveTrack) -> bool:
        return track.misses >= self.max_misses


@dataclass(frozen=True)
class CovarianceDeleter:
    """Delete a track whose covariance trace (over ``indices``, default all components, e.g.
    the position ones) exceeds ``max_trace``."""

    max_trace: float
    indices: Sequence[int] | None = None

    def __post_init__(self) -> None:
        check_positive("max_trace", self.max_trace)
        if self.indices is not None and (
            not len(self.indices) or not all(isinstance(i, int | np.integer) for i in self.indices)
        ):
            raise ConfigError(invalid("indices", self.indices, "state indices (ints) or None"))

    def should_delete(self, track: LiveTrack) -> bool:
        cov = np.asarray(track.belief.cov, float)
        if self.indices is not None:
            idx = np.asarray(self.indices, dtype=np.intp)
            cov = cov[np.ix_(idx, idx)]
        return bool(np.trace(cov) > self.max_trace)


@dataclass(frozen=True)
class ExistenceDeleter:
    """Delete a track whose existence probability is below ``threshold``."""

    threshold: float

    def __post_init__(self) -> None:
        check_probability("threshold", self.threshold)

    def should_delete(self, track: LiveTrack) -> bool:
        return track.existence < self.threshold


class AnyOf:
    """Delete a track when any of ``deleters`` would."""

    def __init__(self, *deleters: Deleter) -> None:
        if not deleters or not all(callable(getattr(d, "should_delete", None)) for d in deleters):
            raise ConfigError(
                invalid("deleters", deleters, "one or more deleters (with should_delete)")
            )
        self.deleters = deleters

    def __repr__(self) -> str:
        return f"AnyOf{self.deleters!r}"

    def should_delete(self, track: LiveTrack) -> bool:
        return any(d.should_delete(track) for d in self.deleters)
