"""Track-oriented MHT as a tracker: :class:`~fusetrack.association.TrackOrientedMHT` with one
filter belief per hypothesis leaf, behind the same ``initial_state / step / run`` interface as
:class:`~fusetrack.tracking.MultiTargetTracker` (Blackman 2004, "Multiple hypothesis tracking
for multiple target tracking", IEEE AES Magazine 19(1); Blackman & Popoli 1999, Ch. 16).

A track (a *family*) is a tree of association histories; its live leaves each carry the
filter's belief conditioned on that history. One scan, per sensor that looked:

1. every leaf's belief is predicted to the scan time (one batched call for the Kalman family);
2. the leaves are scored against the sensor's measurements like tracks
   (:func:`~fusetrack.association.scan_likelihoods`: the rows are the leaf ids) and the MHT
   expands, picks the best global hypothesis and prunes (``n_scan``, ``max_hypotheses``);
3. each surviving child leaf takes its parent's posterior for its measurement (the parent's
   prediction when missed);
4. a family's output (its :class:`~fusetrack.tracking.LiveTrack` belief, hits and misses) is its
   leaf in the best global hypothesis: a decision taken at one scan may be revised by later
   scans, up to ``n_scan`` scans back;
5. measurements that the best global hypothesis leaves unused start tentative families
   (``initiator``); the initiator confirms or drops them and the deleter ends families, as in
   :class:`~fusetrack.tracking.MultiTargetTracker` (whose checks, counters and ``run`` this
   tracker shares).
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, cast

import numpy as np

from ..association import MHTState, TrackHypothesis, TrackOrientedMHT, predict_many
from ..core import ConfigError, Measurement, invalid
from .existence import predict_existence, update_existence
from .state import LiveTrack, TrackerState
from .tracker import TIME_TOLERANCE, MultiTargetTracker, _Births, _ScanRecord


@dataclass(frozen=True, eq=False)
class MHTTrackerState(TrackerState):
    """A :class:`~fusetrack.tracking.TrackerState` (``tracks``: each family's best-hypothesis
    track) plus the MHT's ``hypotheses`` (:class:`~fusetrack.association.MHTState`, leaves keyed
    by leaf id, families by track id) and ``leaf_beliefs``: leaf id -> the filter's belief at
    ``time`` conditioned on that leaf's association history."""

    hypotheses: MHTState = field(default_factory=MHTState)
    leaf_beliefs: Mapping[int, Any] = field(default_factory=dict)


@dataclass
class _Scan:
    """What one scan advances, sensor after sensor."""

    hypotheses: MHTState
    beliefs: dict[int, Any]
    families: dict[int, LiveTrack]
    records: dict[int, _ScanRecord]


class MHTTracker(MultiTargetTracker):
    """Multi-target tracking with track-oriented MHT (module docstring).

    The parameters are those of :class:`~fusetrack.tracking.MultiTargetTracker`, with
    ``associator`` a :class:`~fusetrack.association.TrackOrientedMHT` (``n_scan`` scans of
    deferred decisions, ``max_hypotheses`` leaves per track); ``MultiTargetTracker(...)`` with
    a TrackOrientedMHT builds this class. ``step`` returns a
    :class:`MHTTrackerState`; ``run`` the confirmed tracks as :class:`~fusetrack.core.Track`
    values, each scan's estimate being that of the best global hypothesis at that scan.
    """

    def __init__(
        self, filter: Any, sensors: Any, associator: TrackOrientedMHT, *args: Any, **kw: Any
    ) -> None:
        if not isinstance(associator, TrackOrientedMHT):
            raise ConfigError(invalid("associator", associator, "a TrackOrientedMHT"))
        super().__init__(filter, sensors, associator, *args, **kw)
        if self.birth_only_sensors:
            raise ConfigError(
                invalid(
                    "birth_only_sensors",
                    sorted(self.birth_only_sensors),
                    "none with a TrackOrientedMHT (MultiTargetTracker with a single-scan"
                    " associator has them)",
                )
            )

    def initial_state(self) -> MHTTrackerState:
        """No families, no leaves, no scan yet."""
        base = super().initial_state()
        return MHTTrackerState(initiator_state=base.initiator_state)

    def step(  # type: ignore[override]
        self,
        state: MHTTrackerState,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
        *,
        scanned: Collection[str] | None = None,
    ) -> MHTTrackerState:
        """The state after the scan at ``time`` (module docstring; input handling and errors as
        :meth:`MultiTargetTracker.step`)."""
        if not isinstance(state, MHTTrackerState):
            raise ConfigError(invalid("state", state, "an MHTTrackerState (initial_state())"))
        t = self._check_scan(state, time, measurements, rng, scanned)
        usable, order, stats = self._screen(state.stats, measurements, scanned)
        scan = _Scan(
            state.hypotheses,
            self._predict_leaves(state, t, rng),
            {tr.id: self._predict_family(tr, t) for tr in state.tracks},
            {tr.id: _ScanRecord() for tr in state.tracks},
        )
        births = _Births(state.next_id, state.initiator_state)
        for sid in order:
            cols = [j for j in usable if measurements[j].sensor_id == sid]
            if scan.hypotheses.leaves:
                cols = self._associate_leaves(scan, measurements, cols, sid, rng)
            born = self._births(births, t, sid, [measurements[j] for j in cols], rng)
            for tr, j in born:
                scan.families[tr.id] = tr
                scan.records[tr.id] = _ScanRecord(True, [] if j is None else [(cols[j], 1.0)])
            scan.hypotheses, roots = scan.hypotheses.add_tracks([tr.id for tr, _ in born])
            scan.beliefs.update(zip(roots, (tr.belief for tr, _ in born), strict=True))
        stats = stats.add(births=births.next_id - state.next_id)
        survivors, stats = self._settle(
            scan.families, scan.records, t, state.next_id, bool(order), stats
        )
        gone = set(scan.families) - {tr.id for tr in survivors}  # MHTState.remove_track, at once
        hypotheses = replace(
            scan.hypotheses,
            leaves=tuple(leaf for leaf in scan.hypotheses.leaves if leaf.family not in gone),
        )
        beliefs = {leaf.id: scan.beliefs[leaf.id] for leaf in hypotheses.leaves}
        return MHTTrackerState(
            survivors, t, births.next_id, stats, births.initiator_state, hypotheses, beliefs
        )

    def _predict_leaves(
        self, state: MHTTrackerState, time: float, rng: np.random.Generator | None
    ) -> dict[int, Any]:
        """Every leaf's belief predicted to ``time`` (all in one batched call when they can)."""
        ids = list(state.leaf_beliefs)
        if state.time is None or time - state.time <= TIME_TOLERANCE:
            return dict(state.leaf_beliefs)
        beliefs = [state.leaf_beliefs[i] for i in ids]
        return dict(zip(ids, predict_many(self.filter, beliefs, time - state.time, rng)))

    def _predict_family(self, track: LiveTrack, time: float) -> LiveTrack:
        if time - track.time <= TIME_TOLERANCE:
            return track
        existence = predict_existence(track.existence, self.survival_probability)
        return track.evolve(time=time, existence=existence)

    def _associate_leaves(
        self,
        scan: _Scan,
        measurements: Sequence[Measurement],
        cols: list[int],
        sensor_id: str,
        rng: np.random.Generator | None,
    ) -> list[int]:
        """One MHT scan of the leaves against one sensor's measurements ``cols``: new leaves
        with their beliefs, each family's best-hypothesis track; returns the columns the best
        global hypothesis left unused."""
        p_d = self.p_detect[sensor_id]
        rows = [leaf.id for leaf in scan.hypotheses.leaves]
        chosen = [measurements[j] for j in cols]
        scores, posteriors = self._score(rows, [scan.beliefs[r] for r in rows], chosen, p_d, rng)
        mht = cast(TrackOrientedMHT, self.associator)
        association = mht.associate(scores, rng, scan.hypotheses)
        info = association.info
        children = cast(Mapping[tuple[int, int | None], int], info["children"])
        best = cast(Mapping[int, int], info["best"])
        row_of = {r: k for k, r in enumerate(rows)}
        parent_of: dict[int, tuple[int, int | None]] = {}
        beliefs = {}
        for (parent, j), child in children.items():
            parent_of[child] = (parent, j)
            if j is None:
                beliefs[child] = scan.beliefs[parent]
            else:
                post = posteriors.get((row_of[parent], j))
                beliefs[child] = (
                    post
                    if post is not None
                    else self.filter.update(scan.beliefs[parent], [chosen[j]], rng)
                )
        scan.hypotheses = cast(MHTState, info["state"])
        scan.beliefs = beliefs
        for family, leaves in scan.hypotheses.family_leaves().items():
            leaf = _family_output(leaves, best.get(family))
            parent, j = parent_of[leaf.id]
            record = scan.records[family]
            log_ratios = []
            if j is not None:
                record.used.append((cols[j], 1.0))
                record.detected = True
                log_ratios.append(
                    float(scores.log_likelihood[row_of[parent], j] - scores.log_clutter[j])
                )
            track = scan.families[family]
            existence = update_existence(track.existence, p_d * self.gate_probability, log_ratios)
            scan.families[family] = track.evolve(belief=beliefs[leaf.id], existence=existence)
        return [cols[k] for k in association.unassociated]


def _family_output(leaves: Sequence[TrackHypothesis], best: int | None) -> TrackHypothesis:
    """The family's leaf in the best global hypothesis, else (no consistent choice left it
    one) its highest-scoring leaf."""
    for leaf in leaves:
        if leaf.id == best:
            return leaf
    return max(leaves, key=lambda leaf: leaf.log_score if math.isfinite(leaf.log_score) else -1e300)
