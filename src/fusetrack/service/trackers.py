"""The live node's MCMCDA tracker: online MCMCDA behind the tracker interface
(:class:`~fusetrack.tracking.Tracker`) on the tick's position detections, forgetting what left
its window. The other methods of ``tracker.association.method`` are the library's trackers
(:mod:`fusetrack.tracking`): ``none`` :class:`~fusetrack.tracking.SingleTargetTracker`,
``gnn``/``jpda``/``mht`` :class:`~fusetrack.tracking.MultiTargetTracker`, ``phd``
:class:`~fusetrack.tracking.PHDTracker`. (:class:`~fusetrack.tracking.MCMCDATracker` keeps
committed tracks on a fixed time grid for offline runs; the node publishes the MAP hypothesis'
current tracks every tick, which is what this adapter does.)"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..association import MCMCDA, AssociationState
from ..core import Gaussian, Measurement
from ..tracking import TrackView


@dataclass(frozen=True)
class MCMCDAState:
    """MCMCDA's association state and the tracks of its current MAP hypothesis."""

    association: AssociationState
    confirmed: tuple[TrackView, ...] = ()


class MCMCDAAdapter:
    """Online MCMCDA (:class:`~fusetrack.association.MCMCDA`) behind the tracker interface:
    one MCMCDA step per scan on the position detections ``measurements`` (values ``(2,)``),
    forgetting what left the window (a node runs for days: memory stays flat); the tracks are
    the MAP hypothesis' current ones, their constant-velocity state ``[x, y, vx, vy]`` predicted
    to the scan (:meth:`MCMCDA.current_tracks`). ``rng`` drives the sampler."""

    filter: Any = None

    def __init__(self, mcmcda: MCMCDA) -> None:
        self.mcmcda = mcmcda

    def initial_state(self) -> MCMCDAState:
        return MCMCDAState(self.mcmcda.initial_state())

    def step(
        self,
        state: MCMCDAState,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
        *,
        scanned: Collection[str] | None = None,
    ) -> MCMCDAState:
        y = np.array([np.asarray(m.value, float) for m in measurements]).reshape(-1, 2)
        rng = np.random.default_rng(0) if rng is None else rng
        a = self.mcmcda.forget_past(self.mcmcda.step(state.association, y, rng))
        tracks = self.mcmcda.current_tracks(a)
        return MCMCDAState(a, tuple(TrackView(i, Gaussian(x, p)) for i, (x, p) in tracks.items()))
