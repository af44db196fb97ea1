"""What a multi-target tracker carries from one scan to the next: immutable values only."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any


@dataclass(frozen=True, eq=False)
class LiveTrack:
    """One live track after a scan.

    ``belief`` is the filter's belief at ``time``; ``born`` the time of the measurement that
    started it and ``last_hit`` the last scan in which it was detected. ``scans`` counts the
    scans since its birth (the birth scan is 1), ``hits`` those in which it was detected,
    ``misses`` the missed scans since the last hit. A track is detected in a scan when, for some
    sensor, its association gives it a measurement with probability >= 1/2.
    ``existence`` is its probability of being a real target (:mod:`.existence`).
    ``measurements`` are the indices (into the scan's measurement list) of the measurements its
    hypotheses used in the last scan, with their association ``probabilities``.
    """

    id: int
    belief: Any
    time: float
    born: float
    last_hit: float
    confirmed: bool = False
    scans: int = 1
    hits: int = 1
    misses: int = 0
    existence: float = 0.5
    measurements: tuple[int, ...] = ()
    probabilities: tuple[float, ...] = ()

    def evolve(self, **changes: Any) -> LiveTrack:
        """A copy with ``changes`` (``dataclasses.replace`` without its per-call overhead: a
        tracker makes several per track and scan)."""
        if not _LIVE_TRACK_FIELDS.issuperset(changes):
            unknown = sorted(changes.keys() - _LIVE_TRACK_FIELDS)
            raise TypeError(f"LiveTrack has no field(s) {unknown}")
        new = object.__new__(LiveTrack)
        new.__dict__.update(self.__dict__)
        new.__dict__.update(changes)
        return new


_LIVE_TRACK_FIELDS = frozenset(f.name for f in fields(LiveTrack))


@dataclass(frozen=True)
class TrackerStats:
    """What a tracker did since its initial state (counts, carried in the state so that the
    tracker stays pure).

    ``scans`` processed, of which ``empty_scans`` without a usable measurement; ``measurements``
    received; ``skipped_nonfinite``: measurements left out for a NaN or infinite value or
    covariance (a sensor that saw nothing: never a track's miss or loss by itself);
    ``skipped_unknown_sensor``: measurements of sensors the tracker does not know, left out
    when it was built with ``unknown_sensors="skip"``; ``births`` tentative tracks started,
    ``confirmed`` tracks confirmed, ``dropped`` tentative tracks dropped, ``deleted`` confirmed
    tracks deleted.
    """

    scans: int = 0
    empty_scans: int = 0
    measurements: int = 0
    skipped_nonfinite: int = 0
    skipped_unknown_sensor: int = 0
    births: int = 0
    confirmed: int = 0
    dropped: int = 0
    deleted: int = 0

    def add(self, **counts: int) -> TrackerStats:
        """These stats with ``counts`` added (``stats.add(scans=1, births=2)``; without
        ``dataclasses.replace``'s per-call overhead: a tracker adds a few times per scan)."""
        unknown = counts.keys() - _STATS_FIELDS
        if unknown:
            raise TypeError(f"TrackerStats has no field(s) {sorted(unknown)}")
        new = object.__new__(TrackerStats)
        new.__dict__.update(self.__dict__)
        new.__dict__.update({k: getattr(self, k) + int(v) for k, v in counts.items()})
        return new

    def as_dict(self) -> dict[str, int]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


_STATS_FIELDS = frozenset(f.name for f in fields(TrackerStats))


@dataclass(frozen=True, eq=False)
class TrackerState:
    """The tracker's state after a scan at ``time`` (None before the first): the live tracks,
    tentative and confirmed, in id order, the id the next new track will take, the counters
    ``stats`` and ``initiator_state``, what a scan-level initiator carries between scans (e.g.
    :class:`~fusetrack.tracking.PHDInitiator`'s intensity; None for the others)."""

    tracks: tuple[LiveTrack, ...] = ()
    time: float | None = None
    next_id: int = 0
    stats: TrackerStats = TrackerStats()
    initiator_state: Any = None

    @property
    def confirmed(self) -> tuple[LiveTrack, ...]:
        return tuple(t for t in self.tracks if t.confirmed)

    @property
    def tentative(self) -> tuple[LiveTrack, ...]:
        return tuple(t for t in self.tracks if not t.confirmed)
