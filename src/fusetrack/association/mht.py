"""Track-oriented multiple hypothesis tracking (TOMHT) with N-scan pruning, as a pure function of
an explicit :class:`MHTState` (Blackman 2004, "Multiple hypothesis tracking for multiple target
tracking", IEEE AES Magazine 19(1), Part 2; Blackman & Popoli 1999).

Each target (a *family*, keyed by the tracker's track id) keeps a tree of track hypotheses; its
leaves (:class:`TrackHypothesis`) are the association histories still alive, each with its
cumulative log likelihood ratio ``sum (l_ij - log kappa_j)`` / ``log_missed`` over the scans
(:mod:`fusetrack.association.scores`). One scan:

1. **Expand**: every leaf gets a child per gated measurement and a missed child.
2. **Global hypothesis**: pick one leaf per family, no measurement of any scan used twice, with
   the largest total score: a small integer program (:func:`best_global_hypothesis`, solved by
   :func:`scipy.optimize.milp`); on the first scan of single-leaf families it is the 2-D
   assignment of :class:`~fusetrack.association.GlobalNearestNeighbour`.
3. **N-scan pruning**: in each family keep only the leaves that agree with the family's best leaf
   on every scan older than the last ``n_scan`` (decisions are deferred ``n_scan`` scans;
   ``n_scan = 0`` is GNN), then at most ``max_hypotheses`` leaves per family, best first.

**Rows are leaves.** The scores' rows (``scores.track_ids``) are the state's leaf ids, and the
tracker keeps one belief per leaf: after :meth:`TrackOrientedMHT.associate` a new leaf's belief
is its parent row updated with its measurement (``scan_likelihoods(..., keep_posteriors=True)``),
or the parent's predicted belief when missed. ``info["state"]`` is the new state,
``info["children"]`` maps ``(parent row id, measurement or None)`` to the surviving child's
leaf id, ``info["best"]`` family -> leaf id of the best global hypothesis (its estimate is the
family's output), and ``hypotheses[row id]`` lists each surviving child of that row with its
probability among the row's surviving children (rows with none are absent and listed in
``info["dead"]``). ``unassociated`` are the measurements that no leaf of the best global
hypothesis used. Call with ``state=None`` to start from one root leaf per row, the leaf id being
the row's track id (= its family); :meth:`MHTState.add_track` starts a new family later and
:meth:`MHTState.remove_track` deletes one.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import csr_array

from ..core import ConfigError, FusetrackError, ShapeError, invalid
from .base import Association, ScanLikelihoods, SingleHypothesis
from .scores import log_likelihood_ratios, validate_scores

LOG_IMPOSSIBLE = -1e3
"""Score of a missed child whose probability is zero (``log_missed = -inf``, ``P_D P_G = 1``):
very unlikely instead of impossible, so a family never loses every leaf to it."""


@dataclass(frozen=True)
class TrackHypothesis:
    """A leaf of family ``family``'s tree: measurement index (``None``: missed) chosen at every
    scan from ``birth`` on, and the cumulative log likelihood ratio ``log_score``."""

    id: int
    family: int
    birth: int
    choices: tuple[int | None, ...] = ()
    log_score: float = 0.0

    def used(self) -> Iterator[tuple[int, int]]:
        """``(scan, measurement)`` for every detection on this history."""
        for k, j in enumerate(self.choices):
            if j is not None:
                yield (self.birth + k, j)


@dataclass(frozen=True)
class MHTState:
    """Everything TOMHT carries between scans: the live ``leaves``, the index ``scan`` of the next
    scan, and ``next_id`` (the next unused leaf id)."""

    leaves: tuple[TrackHypothesis, ...] = ()
    scan: int = 0
    next_id: int = 0

    @classmethod
    def for_tracks(cls, track_ids: Sequence[int], scan: int = 0) -> MHTState:
        """One root leaf per track; each leaf id is its track (family) id."""
        ids = [int(t) for t in track_ids]
        roots = tuple(TrackHypothesis(t, t, scan) for t in ids)
        return cls(roots, scan, max(ids, default=-1) + 1)

    def add_track(self, family: int) -> tuple[MHTState, int]:
        """A new family with one root leaf (born at the next scan); returns the state and the
        root's leaf id (the row id of the new track in the next scan's scores)."""
        state, (leaf_id,) = self.add_tracks([family])
        return state, leaf_id

    def add_tracks(self, families: Sequence[int]) -> tuple[MHTState, tuple[int, ...]]:
        """:meth:`add_track` for several new families at once (their root leaf ids, in order)."""
        new = [int(f) for f in families]
        seen = {leaf.family for leaf in self.leaves}
        for f in new:
            if f in seen:
                raise ConfigError(invalid("family", f, "a track id not already in the state"))
            seen.add(f)
        roots = tuple(TrackHypothesis(self.next_id + k, f, self.scan) for k, f in enumerate(new))
        state = replace(self, leaves=(*self.leaves, *roots), next_id=self.next_id + len(new))
        return state, tuple(r.id for r in roots)

    def remove_track(self, family: int) -> MHTState:
        """The state without family ``family`` (a deleted track); unknown families are ignored."""
        return replace(self, leaves=tuple(leaf for leaf in self.leaves if leaf.family != family))

    def family_leaves(self) -> dict[int, list[TrackHypothesis]]:
        """Leaves grouped by family, in order of first appearance."""
        out: dict[int, list[TrackHypothesis]] = {}
        for leaf in self.leaves:
            out.setdefault(leaf.family, []).append(leaf)
        return out


def best_global_hypothesis(leaves: Sequence[TrackHypothesis]) -> dict[int, TrackHypothesis]:
    """The most likely global hypothesis: family -> leaf, at most one leaf per family, no
    ``(scan, measurement)`` used by two chosen leaves, maximum total ``log_score``; every family
    gets a leaf whenever a consistent choice exists (the integer program of Blackman 2004's
    global hypothesis formation, solved with :func:`scipy.optimize.milp`)."""
    families = sorted({leaf.family for leaf in leaves})
    if not leaves:
        return {}
    row_of = {f: r for r, f in enumerate(families)}
    n, nf = len(leaves), len(families)
    scores = np.array([leaf.log_score for leaf in leaves])
    # one "no leaf" variable per family, so that conflicts never make the program infeasible
    big = 1.0 + float(np.abs(scores).sum())
    cost = np.concatenate([-scores, np.full(nf, big)])
    # sparse constraint rows: thousands of families (a scan of false alarms) stay cheap
    family_rows = [row_of[leaf.family] for leaf in leaves] + list(range(nf))
    one_per_family = csr_array(
        (np.ones(n + nf), (family_rows, np.arange(n + nf))), shape=(nf, n + nf)
    )
    users: dict[tuple[int, int], set[int]] = {}
    for k, leaf in enumerate(leaves):
        for key in leaf.used():
            users.setdefault(key, set()).add(k)
    shared = [ks for ks in users.values() if len({leaves[k].family for k in ks}) > 1]
    constraints = [LinearConstraint(one_per_family, 1.0, 1.0)]
    if shared:
        rows = [r for r, ks in enumerate(shared) for _ in ks]
        cols = [k for ks in shared for k in sorted(ks)]
        once = csr_array((np.ones(len(cols)), (rows, cols)), shape=(len(shared), n + nf))
        constraints.append(LinearConstraint(once, -np.inf, 1.0))
    result = milp(
        cost,
        integrality=np.ones(n + nf),
        bounds=Bounds(0, 1),
        constraints=constraints,
        options={"mip_rel_gap": 0.0},  # the optimum, not one within HiGHS's default 1e-4
    )
    if result.x is None:  # cannot happen: the "no leaf" variables keep it feasible
        raise FusetrackError(f"global hypothesis: the integer program failed ({result.message})")
    chosen = np.flatnonzero(np.round(result.x[:n]) == 1)
    return {leaves[int(k)].family: leaves[int(k)] for k in chosen}


def n_scan_prune(
    leaves: Sequence[TrackHypothesis],
    best: Mapping[int, TrackHypothesis],
    last_scan: int,
    n_scan: int,
) -> list[TrackHypothesis]:
    """The leaves that agree with their family's best leaf on every scan ``<= last_scan -
    n_scan`` (``n_scan = 0``: the best leaves only); families without a best leaf keep all."""
    kept = []
    for leaf in leaves:
        b = best.get(leaf.family)
        if b is None:
            kept.append(leaf)
            continue
        upto = last_scan - n_scan - leaf.birth + 1  # number of fixed choices
        if upto <= 0 or leaf.choices[:upto] == b.choices[:upto]:
            kept.append(leaf)
    return kept


@dataclass(frozen=True)
class TrackOrientedMHT:
    """Track-oriented MHT: decisions deferred ``n_scan`` scans, at most ``max_hypotheses``
    leaves per family (see the module docstring for the row = leaf convention)."""

    n_scan: int = 2
    max_hypotheses: int = 20

    def __post_init__(self) -> None:
        if int(self.n_scan) != self.n_scan or self.n_scan < 0:
            raise ConfigError(invalid("n_scan", self.n_scan, "an int >= 0"))
        if int(self.max_hypotheses) != self.max_hypotheses or self.max_hypotheses < 1:
            raise ConfigError(invalid("max_hypotheses", self.max_hypotheses, "an int >= 1"))

    def associate(
        self,
        scores: ScanLikelihoods,
        rng: np.random.Generator | None = None,
        state: MHTState | None = None,
    ) -> Association:
        validate_scores(scores, "TrackOrientedMHT")
        state = MHTState.for_tracks(scores.track_ids) if state is None else state
        by_id = {leaf.id: leaf for leaf in state.leaves}
        if sorted(by_id) != sorted(scores.track_ids):
            raise ShapeError(
                invalid(
                    "scores.track_ids", scores.track_ids, f"the state's leaf ids {sorted(by_id)}"
                )
            )
        children, parent_of = self._expand(scores, state, by_id)
        best = best_global_hypothesis(children)
        kept = self._prune(children, best, state.scan)
        return self._association(scores, state, kept, best, parent_of)

    def _expand(
        self, scores: ScanLikelihoods, state: MHTState, by_id: Mapping[int, TrackHypothesis]
    ) -> tuple[list[TrackHypothesis], dict[int, tuple[int, int | None]]]:
        """Every leaf's children (gated measurements and missed), with fresh ids."""
        weights = log_likelihood_ratios(scores)
        m = scores.shape[1]
        children: list[TrackHypothesis] = []
        parent_of: dict[int, tuple[int, int | None]] = {}
        next_id = state.next_id
        for i, row_id in enumerate(scores.track_ids):
            parent = by_id[row_id]
            options: list[int | None] = [
                int(j) for j in np.flatnonzero(np.isfinite(weights[i, :m]))
            ]
            for j in [*options, None]:
                w = weights[i, m if j is None else j]
                w = LOG_IMPOSSIBLE if not math.isfinite(w) else float(w)
                child = TrackHypothesis(
                    next_id, parent.family, parent.birth, (*parent.choices, j), parent.log_score + w
                )
                children.append(child)
                parent_of[next_id] = (row_id, j)
                next_id += 1
        return children, parent_of

    def _prune(
        self, children: list[TrackHypothesis], best: Mapping[int, TrackHypothesis], scan: int
    ) -> list[TrackHypothesis]:
        """N-scan pruning, then the ``max_hypotheses`` best leaves per family (best leaf kept)."""
        kept = n_scan_prune(children, best, scan, self.n_scan)
        out: list[TrackHypothesis] = []
        by_family: dict[int, list[TrackHypothesis]] = {}
        for leaf in kept:
            by_family.setdefault(leaf.family, []).append(leaf)
        for family, leaves in by_family.items():
            top = best.get(family)
            leaves.sort(key=lambda leaf: (leaf is not top, -leaf.log_score))
            out.extend(leaves[: self.max_hypotheses])
        return out

    def _association(
        self,
        scores: ScanLikelihoods,
        state: MHTState,
        kept: list[TrackHypothesis],
        best: Mapping[int, TrackHypothesis],
        parent_of: Mapping[int, tuple[int, int | None]],
    ) -> Association:
        by_row: dict[int, list[TrackHypothesis]] = {}
        for leaf in kept:
            by_row.setdefault(parent_of[leaf.id][0], []).append(leaf)
        hypotheses = {}
        for row_id, leaves in by_row.items():
            s = np.array([leaf.log_score for leaf in leaves])
            p = np.exp(s - s.max())
            p /= p.sum()
            hypotheses[row_id] = tuple(
                SingleHypothesis(row_id, parent_of[leaf.id][1], float(q))
                for leaf, q in zip(leaves, p, strict=True)
            )
        used = {leaf.choices[-1] for leaf in best.values()}
        new_state = MHTState(tuple(kept), state.scan + 1, state.next_id + len(parent_of))
        info = {
            "state": new_state,
            "children": {parent_of[leaf.id]: leaf.id for leaf in kept},
            "best": {family: leaf.id for family, leaf in best.items()},
            "dead": tuple(r for r in scores.track_ids if r not in by_row),
        }
        unassociated = tuple(j for j in range(scores.shape[1]) if j not in used)
        return Association(hypotheses, unassociated, info)
