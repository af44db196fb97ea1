"""One target: any :class:`~fusetrack.core.Filter` behind the tracker interface
(:class:`~.protocol.Tracker`), so that a node or an application steps one target and several
the same way."""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core import Measurement, filter_step
from .protocol import TrackView

TIME_TOLERANCE = 1e-9


@dataclass(frozen=True)
class SingleTargetState:
    """The one track's belief at ``time`` (None before the first step: the prior is drawn
    then)."""

    belief: Any
    time: float

    @property
    def confirmed(self) -> tuple[TrackView, ...]:
        return () if self.belief is None else (TrackView(0, self.belief),)


class SingleTargetTracker:
    """A filter as a one-track tracker: each step is one :func:`~fusetrack.core.filter_step`
    to the step's time (a predict only when it is later), so stepping it as
    :func:`~fusetrack.filters.run_filter` steps its filter gives the same estimates;
    ``prior(rng)`` gives the initial belief, and :meth:`restart` the track from it."""

    def __init__(
        self, filt: Any, prior: Callable[[np.random.Generator | None], Any], start: float
    ) -> None:
        self.filter = filt
        self.prior = prior
        self.start = float(start)

    def initial_state(self) -> SingleTargetState:
        return SingleTargetState(None, self.start)

    def restart(
        self, state: SingleTargetState, rng: np.random.Generator | None = None
    ) -> SingleTargetState:
        """The track from the prior again, at the state's time (a filter that diverged)."""
        return SingleTargetState(self.prior(rng), state.time)

    def step(
        self,
        state: SingleTargetState,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
        *,
        scanned: Collection[str] | None = None,
    ) -> SingleTargetState:
        """One :func:`filter_step` to ``time`` with ``measurements`` (``scanned`` is unused)."""
        belief = self.prior(rng) if state.belief is None else state.belief
        dt = time - state.time
        if dt > TIME_TOLERANCE:
            return SingleTargetState(filter_step(self.filter, belief, dt, measurements, rng), time)
        if measurements:
            belief = filter_step(self.filter, belief, 0.0, measurements, rng)
        return SingleTargetState(belief, state.time)
