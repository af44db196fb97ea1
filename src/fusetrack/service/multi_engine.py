"""Several targets inside the node: position detections associated by online MCMCDA, behind the
same :class:`~.engine.Engine` interface as the single-target :class:`~.engine.FusionEngine`.

``tracker.association.method: mcmcda``. Every tick, the tick's readings become position
detections (:func:`detections`):

* a ``position_fix`` reading is one detection (its x, y);
* a ``range_bearing`` plot is one detection, ``s + r [cos(b + heading), sin(b + heading)]``;
* with the grid tracker (``filter: grid``), every other reading of the tick is fused on the grid
  without a temporal prior and the peaks of that likelihood are detections (Kushwaha 2010,
  Ch. III: "raw observations obtained from the multimodal sensor fusion and peak detection",
  :func:`~fusetrack.association.likelihood_peaks`).

The detections go to :class:`~fusetrack.association.mcmcda.MCMCDA` (one step per tick, its
sliding window and track identities), and each track of its current MAP hypothesis is published
as a :class:`~.schema.TrackState` with the track's id: the constant-velocity Kalman state of
the track through its observations, predicted to the tick (:meth:`MCMCDA.current_tracks`). A
tick may publish no track or several. The sampler's random numbers come from the tracker's seed,
so a replay of the same readings through a fresh engine gives the same tracks.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..association.mcmcda import MCMCDA, AssociationState, MCMCDAConfig
from ..association.peaks import likelihood_peaks
from .alignment import Reading
from .config import NetworkConfig
from .engine import track_state
from .grid_cells import CellLikelihoods, grid_of
from .schema import TrackState

_POSITION_KINDS = ("position_fix", "range_bearing")


def detections(
    cfg: NetworkConfig, readings: Sequence[Reading], cells: CellLikelihoods | None
) -> np.ndarray:
    """The tick's position detections ``(k, 2)`` (see the module docstring), in reading order,
    then the grid peaks."""
    kinds = {s.id: s for s in cfg.sensors}
    out: list[list[float]] = []
    rest: list[Reading] = []
    for r in readings:
        s = kinds[r.sensor]
        if s.kind == "position_fix":
            out.append([float(r.value[0]), float(r.value[1])])
        elif s.kind == "range_bearing":
            assert s.position is not None
            a = float(r.value[1]) + s.heading
            out.append(
                [
                    s.position[0] + float(r.value[0]) * math.cos(a),
                    s.position[1] + float(r.value[0]) * math.sin(a),
                ]
            )
        else:
            rest.append(r)
    if cells is not None and rest:
        fused = cells.fused(rest, cfg.tracker.grid.fusion)
        if fused is not None:
            g = cells.grid
            peaks = likelihood_peaks(fused, g.x, g.y, 0.3, 4.0 / g.size)
            out.extend(peaks.tolist())
    return np.array(out, dtype=float).reshape(-1, 2)


def associate(
    mcmcda: MCMCDA, state: AssociationState, y: np.ndarray, rng: np.random.Generator
) -> tuple[AssociationState, dict[int, tuple[np.ndarray, np.ndarray]]]:
    """One MCMCDA step on the tick's detections ``y (k, 2)``: the new association state and the
    current tracks by id (the Kalman state and covariance of each, predicted to the tick). The
    engine's only call into :mod:`fusetrack.association.mcmcda`."""
    state = mcmcda.forget_past(
        mcmcda.step(state, y, rng)
    )  # a node runs for days: memory stays flat
    return state, dict(mcmcda.current_tracks(state))


class MultiTargetEngine:
    """The node's multi-target tracker (module docstring)."""

    def __init__(self, cfg: NetworkConfig, start: float) -> None:
        a = cfg.tracker.association
        x0, x1, y0, y1 = cfg.area
        self.cfg = cfg
        self.mcmcda = MCMCDA(
            MCMCDAConfig(
                dt=1.0 / cfg.fusion.rate_hz,
                area=(x1 - x0) * (y1 - y0),
                **a.model_dump(exclude={"method"}),  # the section's fields are MCMCDAConfig's
            ),
        )
        self.rng = np.random.default_rng(cfg.tracker.seed)
        self.association = self.mcmcda.initial_state()
        self.cells = CellLikelihoods(cfg, grid_of(cfg)) if cfg.tracker.filter == "grid" else None
        self.time = float(start)
        self.resets = 0
        self.last_detections = np.empty((0, 2))

    def step_all(self, tick: int, t: float, readings: Sequence[Reading]) -> list[TrackState]:
        """Associate the tick's detections; publish every current track."""
        y = detections(self.cfg, readings, self.cells)
        self.association, tracks = associate(self.mcmcda, self.association, y, self.rng)
        self.last_detections = y
        self.time = t
        # ids from 1, as the single-target trackers'
        return [
            track_state(ident + 1, tick, t, x, p, (0, 1), readings)
            for ident, (x, p) in tracks.items()
        ]
