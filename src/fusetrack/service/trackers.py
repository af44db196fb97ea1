"""The trackers a node steps, one interface for all (``tracker.association.method``).

A tracker is pure, as :class:`~fusetrack.tracking.MultiTargetTracker` is: ``initial_state()``,
then ``state = tracker.step(state, time, measurements, rng, scanned=None)`` per scan; the
state's ``confirmed`` tracks have an ``id`` (from 0) and a ``belief``; ``tracker.filter`` is the
filter whose ``estimate`` (when it has one) summarises a belief.

* ``none``: :class:`SingleTargetTracker`, the configured filter as a one-track tracker: each
  step is one :func:`~fusetrack.core.filter_step` to the step's time (a predict only when it is
  later), so stepping it as :func:`~fusetrack.filters.run_filter` steps its filter gives the
  same estimates;
* ``gnn``, ``jpda``, ``mht``: :class:`~fusetrack.tracking.MultiTargetTracker` itself;
* ``phd``: :class:`PhdTracker`, the GM-PHD filter's intensity with its labelled components as
  tracks;
* ``mcmcda``: :class:`MCMCDAAdapter`, online MCMCDA on position detections (swap it for a
  tracking-layer MCMCDA tracker of the same interface when there is one).
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from ..association import MCMCDA, AssociationState
from ..core import Gaussian, Measurement, filter_step
from ..filters import GMPHDFilter, PhdIntensity, extract_states

TIME_TOLERANCE = 1e-9


@dataclass(frozen=True)
class NodeTrack:
    """A track of a tracker's state: its id and belief."""

    id: int
    belief: Any


class NodeTracker(Protocol):
    """What the node's engine steps (module docstring)."""

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


def summary(filt: Any, belief: Any) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance of a belief: the filter's ``estimate`` when it has one."""
    estimate = getattr(filt, "estimate", None)
    s = estimate(belief) if callable(estimate) else belief
    return np.asarray(s.mean), np.asarray(s.cov)


# -- one target ------------------------------------------------------------------------------


@dataclass(frozen=True)
class SingleTargetState:
    """The one track's belief at ``time`` (None before the first step: the prior is drawn
    then)."""

    belief: Any
    time: float

    @property
    def confirmed(self) -> tuple[NodeTrack, ...]:
        return () if self.belief is None else (NodeTrack(0, self.belief),)


class SingleTargetTracker:
    """A filter as a one-track tracker (module docstring); ``prior(rng)`` gives the initial
    belief, and :meth:`restart` the track from it."""

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


# -- GM-PHD ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class PhdState:
    """The PHD intensity after the scan at ``time``, its tracks, and the public id of every
    label ever extracted (ids count from 0 in order of first extraction)."""

    intensity: PhdIntensity
    time: float | None = None
    confirmed: tuple[NodeTrack, ...] = ()
    ids: Mapping[int, int] = field(default_factory=dict)


class PhdTracker:
    """The GM-PHD filter as a tracker: predict to the scan, update with the scan's readings
    (every sensor in ``scanned``, default all, that sent nothing looked and saw nothing: a NaN
    reading, the missed-detection term only), then the components of weight above
    ``threshold`` are the tracks (Vo & Ma 2006, Table III). A label shared by several of them
    stays with the heaviest; the others get fresh labels, kept from then on."""

    def __init__(self, phd: GMPHDFilter, threshold: float = 0.5) -> None:
        self.filter = phd
        self.threshold = float(threshold)

    def initial_state(self) -> PhdState:
        return PhdState(PhdIntensity.empty(self.filter.motion.dim))

    def step(
        self,
        state: PhdState,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
        *,
        scanned: Collection[str] | None = None,
    ) -> PhdState:
        dt = 0.0 if state.time is None else max(0.0, time - state.time)
        v = self.filter.predict(state.intensity, dt, rng)
        heard = {m.sensor_id for m in measurements}
        looked = self.filter.sensors if scanned is None else scanned
        silent = [
            Measurement(time, sid, np.full(int(getattr(s, "value_size", s.dim)), np.nan))
            for sid, s in self.filter.sensors.items()
            if sid in looked and sid not in heard
        ]
        v = _distinct_labels(self.filter.update(v, [*measurements, *silent], rng), self.threshold)
        ids = dict(state.ids)
        tracks: dict[int, NodeTrack] = {}
        for label, mean, cov in extract_states(v, self.threshold):
            ident = ids.setdefault(label, len(ids))
            tracks.setdefault(ident, NodeTrack(ident, Gaussian(mean, cov)))
        return PhdState(v, time, tuple(tracks[i] for i in sorted(tracks)), ids)


def _distinct_labels(v: PhdIntensity, threshold: float) -> PhdIntensity:
    """``v`` with a fresh label on every component above ``threshold`` whose label a heavier
    one above it already has (two targets born of one birth component share its label)."""
    labels, nxt, seen = v.labels.copy(), int(v.next_label), set()
    for i in np.argsort(-v.weights, kind="stable"):
        if v.weights[i] <= threshold:
            break
        if labels[i] in seen:
            labels[i], nxt = nxt, nxt + 1
        seen.add(int(labels[i]))
    if nxt == v.next_label:
        return v
    return PhdIntensity(v.weights, v.means, v.covs, labels, nxt)


# -- MCMCDA ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class MCMCDAState:
    """MCMCDA's association state and the tracks of its current MAP hypothesis."""

    association: AssociationState
    confirmed: tuple[NodeTrack, ...] = ()


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
        return MCMCDAState(a, tuple(NodeTrack(i, Gaussian(x, p)) for i, (x, p) in tracks.items()))
