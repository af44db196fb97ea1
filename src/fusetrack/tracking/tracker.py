"""A multi-target tracker assembled from parts: a filter, sensors, an associator, an initiator and
a deleter (the Stone Soup way), pure: ``state = tracker.step(state, time, measurements, rng)``.

One scan (all the measurements of one time, from any sensors) goes through, per sensor that
scanned (each sensor's measurements are associated on their own: a target gives at most one
measurement per sensor, but may give one to each):

1. every live track is predicted to the scan time (``filter.predict``), its existence with
   ``P_S`` (:mod:`.existence`);
2. the confirmed tracks are scored against the sensor's measurements with the tracks' own
   filter (:func:`~fusetrack.association.scan_likelihoods`: ``log P_D p(z | track)`` behind a
   Mahalanobis gate) and the associator turns the scores of the gated block (the tracks with a
   measurement in their gate, the measurements in some gate; the others are missed or left
   unassociated, which changes no joint event's odds) into weighted hypotheses
   (:class:`~fusetrack.association.Associator`: GNN, JPDA or any other single-scan one, hard
   or soft); each track's belief becomes the posterior of a probability-1 hypothesis, the
   prediction when missed, or the PDA combination of several (:mod:`.mixing`), and its
   existence is updated (IPDA);
3. the tentative tracks are scored and associated the same way against what the confirmed ones
   left, so a track that is not yet confirmed never steals a confirmed track's measurement;
4. the measurements still left may start tentative tracks (``initiator.birth`` for each, or a
   scan-level initiator's ``births``, e.g. :class:`~fusetrack.tracking.PHDInitiator`).

For the Kalman family a scan runs on arrays (:mod:`fusetrack.association.batch`): the
predictions of all tracks are one batched filter call, all tracks are gated and scored against
a sensor's measurements once (one batched update of the gated pairs, whose posteriors stay
stacked; the confirmed and the tentative pass take their blocks), the associator answers with
a weight matrix when it can (``association_weights``), and the PDA mixture and the existence
of all tracks are one array pass each (:func:`.mixing.combine_stacked`,
:func:`.existence.update_existences`); any other filter goes track by track, with the same
results. So a scan of thousands of false alarms stays cheap.

A sensor in ``birth_only_sensors`` only starts tracks: its measurements inside a live track's
gate start nothing, the others go to the initiator; no track is updated by it.

After the scan every track counts a hit or a miss (none when no sensor looked); the initiator
confirms or drops tentative tracks (M-of-N), the deleter ends confirmed ones. Everything lives in
a :class:`TrackerState`, with :class:`TrackerStats` counters. Bad input is a clear error before
any work (an unknown sensor by default, a wrong size, a scan before the last one: the message
names both times) or a counted skip (NaN reports; unknown sensors with
``unknown_sensors="skip"``), never a crash or a silently lost track.

Track-oriented MHT needs a belief per hypothesis leaf: :class:`~fusetrack.tracking.MHTTracker`;
online MCMCDA on position reports: :class:`~fusetrack.tracking.MCMCDATracker`. Both have the
same ``initial_state / step / run`` interface.

Example: two targets in a 100 m square, a position sensor, one false alarm per scan; tracks
are confirmed when detected in 3 of their first 4 scans::

    >>> import numpy as np
    >>> from fusetrack.core import Gaussian, Measurement
    >>> from fusetrack.filters import KalmanFilter
    >>> from fusetrack.motion import ConstantVelocity
    >>> from fusetrack.sensors import PositionFix
    >>> from fusetrack.tracking import (InverseMeasurementPrior, MissedCountDeleter,
    ...     MofNInitiator, MultiTargetTracker)
    >>> tag = PositionFix("tag", cov=0.25 * np.eye(2))
    >>> kf = KalmanFilter(ConstantVelocity(ndim=2, q=0.1), [tag])
    >>> from fusetrack.association import GlobalNearestNeighbour
    >>> tracker = MultiTargetTracker(
    ...     kf, [tag], GlobalNearestNeighbour(),
    ...     initiator=MofNInitiator(3, 4, InverseMeasurementPrior(
    ...         [tag], Gaussian(np.zeros(4), np.diag([0, 0, 25.0, 25.0])))),
    ...     deleter=MissedCountDeleter(3), p_detect=0.9, clutter_density=1e-4)
    >>> rng = np.random.default_rng(1)
    >>> zs = []
    >>> for k in range(10):
    ...     for x0, v in (([0.0, 0.0], [5.0, 5.0]), ([0.0, 50.0], [5.0, -5.0])):
    ...         zs.append(Measurement(k, "tag", np.add(x0, np.multiply(v, k)) + rng.normal(0, 0.5, 2)))
    ...     zs.append(Measurement(k, "tag", rng.uniform(0, 100, 2)))  # a false alarm
    >>> tracks = tracker.run(zs, rng)
    >>> [(t.id, len(t)) for t in tracks]
    [(0, 10), (1, 10)]
    >>> np.round(tracks[0].means[-1, :2])
    array([45., 45.])

``tracks`` are :class:`~fusetrack.core.Track` values with their persistent ``id``, from the
birth scan on (tentative scans included); tracks never confirmed are left out.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..association import (
    Association,
    Associator,
    PairPosteriors,
    ScanLikelihoods,
    TrackOrientedMHT,
    batchable,
    gate_threshold,
    hypothesis_weights,
    mahalanobis_squared,
    predict_stacked,
    scan_likelihoods,
    stack_gaussians,
)
from ..core import (
    ConfigError,
    Gaussian,
    Measurement,
    MeasurementError,
    SensorModel,
    Track,
    UnknownSensorError,
    as_measurements,
    group_by_time,
    invalid,
    order_by_time,
)
from ..filters import as_sensor_map, validate_measurement
from .deleters import Deleter
from .existence import predict_existence, update_existences
from .initiators import Initiator
from .mixing import combine_hypotheses, combine_stacked
from .state import LiveTrack, TrackerState, TrackerStats

TIME_TOLERANCE = 1e-9  # measurements closer in time than this form one scan


def _in_range(name: str, value: object, lo: float, hi: float, valid: str = "") -> float:
    """``float(value)`` if it is in ``(lo, hi]``, else :class:`ConfigError`."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        v = math.nan
    if not lo < v <= hi:
        raise ConfigError(invalid(name, value, valid or f"a number in ({lo:g}, {hi:g}]"))
    return v


def _per_sensor(
    name: str, value: object, sensors: Collection[str], lo: float, hi: float
) -> dict[str, float]:
    """``value`` (one number or ``sensor_id -> number``) as a dict over ``sensors``, each in
    ``(lo, hi]``, else :class:`ConfigError`."""
    valid = f"a number in ({lo:g}, {hi:g}], or a mapping sensor_id -> such a number for {sorted(sensors)}"
    if not isinstance(value, Mapping):
        v = _in_range(name, value, lo, hi, valid)
        return dict.fromkeys(sensors, v)
    missing = sorted(set(sensors) - set(value))
    if missing:
        raise ConfigError(invalid(name, dict(value), valid + f" (missing {missing})"))
    return {s: _in_range(f"{name}[{s!r}]", value[s], lo, hi, valid) for s in sensors}


def _require(obj: Any, name: str, methods: Sequence[str], what: str) -> None:
    missing = [m for m in methods if not callable(getattr(obj, m, None))]
    if missing:
        raise ConfigError(invalid(name, obj, f"{what} (missing {', '.join(missing)})"))


def _check_association(associator: Any, association: Association, n: int) -> None:
    """Raise :class:`ConfigError` when an associator's answer names measurements outside the
    scan or gives a negative or non-finite probability."""
    indices = [h.measurement for hs in association.hypotheses.values() for h in hs]
    indices += list(association.unassociated)
    bad = [k for k in indices if k is not None and not 0 <= k < n]
    probs = [h.probability for hs in association.hypotheses.values() for h in hs]
    if bad or not all(math.isfinite(p) and p >= 0 for p in probs):
        raise ConfigError(
            invalid(
                "associator",
                associator,
                f"an Association with measurement indices in [0, {n}) and probabilities >= 0"
                f" (got indices {bad}, probabilities {probs})",
            )
        )


def _birth_only(value: Any, sensors: Collection[str]) -> frozenset[str]:
    """``birth_only_sensors`` as a set of known sensor ids, else :class:`ConfigError`."""
    if isinstance(value, str) or not isinstance(value, Iterable):
        raise ConfigError(invalid("birth_only_sensors", value, "a collection of sensor ids"))
    ids = list(value)
    unknown = [s for s in ids if s not in sensors]
    if unknown:
        raise ConfigError(
            invalid("birth_only_sensors", ids, f"ids of the sensors {sorted(sensors)}")
        )
    return frozenset(ids)


def _checked_weights(associator: Any, answer: Any, shape: tuple[int, int]) -> np.ndarray:
    """An associator's ``association_weights`` answer: ``(T, M + 1)`` finite weights >= 0 and
    unassociated indices in ``[0, M)``, else :class:`ConfigError`."""
    t, m = shape
    weights = np.asarray(getattr(answer, "weights", None), dtype=float)
    left = list(getattr(answer, "unassociated", ()))
    if (
        weights.shape != (t, m + 1)
        or not np.isfinite(weights).all()
        or (weights < 0).any()
        or not all(0 <= k < m for k in left)
    ):
        raise ConfigError(
            invalid(
                "associator",
                associator,
                f"AssociationWeights with finite weights >= 0 of shape ({t}, {m + 1}) and"
                f" unassociated indices in [0, {m})",
            )
        )
    return weights


def _normalised_rows(weights: np.ndarray) -> np.ndarray:
    """Each row of ``weights`` ``(T, M + 1)`` divided by its sum; a row of zeros (no
    hypothesis with positive weight) becomes missed with weight 1."""
    total = weights.sum(axis=1, keepdims=True)
    out = np.divide(weights, total, out=np.zeros_like(weights), where=total > 0)
    out[total[:, 0] <= 0, -1] = 1.0
    return out


def _all_finite(measurements: Sequence[Measurement]) -> bool:
    """True when every measurement (vector values, checked) has finite values and none has
    its own covariance (one array test for the common scan; else :func:`_usable` each)."""
    if any(m.covariance is not None for m in measurements):
        return False
    return not measurements or bool(
        np.isfinite(np.concatenate([m.value for m in measurements])).all()
    )


def _usable(m: Measurement) -> bool:
    """False when the value or its own covariance has a NaN or infinite entry."""
    cov, value = m.covariance, m.value
    if isinstance(value, np.ndarray) and not np.isfinite(value).all():  # Measurement.is_finite
        return False
    return cov is None or bool(np.isfinite(cov).all())


@dataclass
class _Births:
    """What the births of one scan advance: the next track id and the initiator's state."""

    next_id: int
    initiator_state: Any


@dataclass
class _ScanRecord:
    """What one scan did to one track: whether it was detected, with which measurements."""

    detected: bool = False
    used: list[tuple[int, float]] = field(default_factory=list)


class MultiTargetTracker:
    """A multi-target tracker (module docstring), pure: it holds only its parts.

    Parameters
    ----------
    filter:
        a :class:`~fusetrack.core.LikelihoodFilter` (``predict``, ``update``,
        ``update_with_likelihood``) for one target; every track runs it on its own belief.
    sensors:
        the sensor models by ``sensor_id`` (mapping or sequence); None: the filter's own
        ``filter.sensors``. Each measurement is gated with its own sensor.
    associator:
        any :class:`~fusetrack.association.Associator` (``associate(scores, rng)``): GNN, JPDA;
        a :class:`~fusetrack.association.TrackOrientedMHT` makes this tracker an
        :class:`~fusetrack.tracking.MHTTracker` (the same interface, a belief per hypothesis
        leaf).
    initiator:
        an :class:`~fusetrack.tracking.Initiator` (:class:`MofNInitiator`, ...).
    deleter:
        a :class:`~fusetrack.tracking.Deleter` (:class:`MissedCountDeleter`, :class:`AnyOf`, ...).
    p_detect:
        ``P_D`` in ``(0, 1]``, one for all sensors or ``sensor_id -> P_D``.
    clutter_density:
        false alarms per scan per unit measurement volume (``lambda c(z)``, > 0), one number or
        ``sensor_id -> density`` (sensors measure in different units).
    gate_probability:
        ``P_G`` in ``(0, 1]``: the gate holds this fraction of a track's measurements (1: no gate).
    survival_probability:
        ``P_S`` in ``(0, 1]``: a target's probability of surviving from one scan to the next,
        for the existence probability only.
    unknown_sensors:
        ``"raise"`` (default): a measurement of a sensor not in ``sensors`` raises
        :class:`~fusetrack.core.UnknownSensorError` before any work; ``"skip"``: it is left out
        and counted in ``state.stats.skipped_unknown_sensor`` (a live feed with other sensors).
    birth_only_sensors:
        ids of sensors whose measurements only start tracks: a measurement inside the gate of
        a live track (confirmed or tentative, as predicted or updated by the sensors before it
        in the scan) starts nothing, one outside every gate goes to the initiator, and no track
        is updated, counted as hit or missed, or has its existence changed by such a sensor
        (e.g. triangulated points that start trackers of bearings). Their ``p_detect`` and
        ``clutter_density`` are not needed.
    """

    def __new__(cls, *args: Any, **kw: Any) -> MultiTargetTracker:
        """With a :class:`~fusetrack.association.TrackOrientedMHT` as ``associator`` the
        tracker is an :class:`~fusetrack.tracking.MHTTracker` (MHT needs a belief per
        hypothesis leaf), built with the same arguments."""
        associator = args[2] if len(args) > 2 else kw.get("associator")
        if cls is MultiTargetTracker and isinstance(associator, TrackOrientedMHT):
            from .mht_tracker import MHTTracker  # here: mht_tracker builds on this module

            return super().__new__(MHTTracker)
        return super().__new__(cls)

    def __init__(
        self,
        filter: Any,
        sensors: Mapping[str, SensorModel] | Sequence[SensorModel] | None,
        associator: Associator,
        initiator: Initiator,
        deleter: Deleter,
        p_detect: float | Mapping[str, float],
        clutter_density: float | Mapping[str, float],
        gate_probability: float = 0.99,
        *,
        survival_probability: float = 0.99,
        unknown_sensors: Literal["raise", "skip"] = "raise",
        birth_only_sensors: Collection[str] = (),
    ) -> None:
        _require(
            filter, "filter", ("predict", "update", "update_with_likelihood"), "a LikelihoodFilter"
        )
        _require(associator, "associator", ("associate",), "an Associator")
        _require(initiator, "initiator", ("birth", "status"), "an Initiator")
        _require(deleter, "deleter", ("should_delete",), "a Deleter")
        if sensors is None:
            sensors = getattr(filter, "sensors", None)
            if not isinstance(sensors, Mapping):
                raise ConfigError(
                    invalid("sensors", None, "sensor models (the filter has no sensors map)")
                )
        self.sensors = as_sensor_map(sensors)
        if not self.sensors:
            raise ConfigError(invalid("sensors", sensors, "at least one sensor model"))
        own = getattr(filter, "sensors", None)
        if isinstance(own, Mapping) and set(self.sensors) - set(own):
            raise ConfigError(
                invalid(
                    "sensors", sorted(self.sensors), f"sensors the filter knows ({sorted(own)})"
                )
            )
        self.filter = filter
        # each sensor's report length (validate_measurement's m): the fast path of the checks
        self._value_sizes = {
            sid: int(getattr(s, "value_size", s.dim)) for sid, s in self.sensors.items()
        }
        self.associator = associator
        self.initiator = initiator
        self.deleter = deleter
        self.birth_only_sensors = _birth_only(birth_only_sensors, self.sensors)
        associating = [s for s in self.sensors if s not in self.birth_only_sensors]
        self.p_detect = _per_sensor("p_detect", p_detect, associating, 0.0, 1.0)
        self.clutter_density = _per_sensor(
            "clutter_density", clutter_density, associating, 0.0, math.inf
        )
        self.gate_probability = _in_range("gate_probability", gate_probability, 0.0, 1.0)
        self.survival_probability = _in_range(
            "survival_probability", survival_probability, 0.0, 1.0
        )
        self.birth_existence = _in_range(
            "initiator.existence", getattr(initiator, "existence", None), 0.0, 1.0
        )
        if unknown_sensors not in ("raise", "skip"):
            raise ConfigError(invalid("unknown_sensors", unknown_sensors, "'raise' or 'skip'"))
        self.unknown_sensors = unknown_sensors

    def __repr__(self) -> str:
        return (
            f"MultiTargetTracker(filter={type(self.filter).__name__}, sensors={sorted(self.sensors)}, "
            f"associator={self.associator!r}, initiator={self.initiator!r}, deleter={self.deleter!r})"
        )

    def initial_state(self) -> TrackerState:
        """No tracks, no scan yet (and a scan-level initiator's ``initial_state()``)."""
        start = getattr(self.initiator, "initial_state", None)
        return TrackerState(initiator_state=start() if callable(start) else None)

    # -- one scan ------------------------------------------------------------------------------

    def _known(self, measurements: Iterable[Measurement]) -> list[Measurement]:
        """The measurements of known sensors: with ``unknown_sensors="raise"`` an unknown one
        raises :class:`~fusetrack.core.UnknownSensorError`, with ``"skip"`` it is left out."""
        out = []
        for m in measurements:
            if not isinstance(m, Measurement):
                raise MeasurementError(invalid("measurements", m, "Measurement objects"))
            if m.sensor_id in self.sensors or self.unknown_sensors == "raise":
                out.append(m)
        return out

    def _check_measurements(self, measurements: Iterable[Measurement]) -> None:
        """Unknown sensors (unless skipped), wrong sizes and non-vector values raise
        :class:`MeasurementError`."""
        sizes = self._value_sizes
        for m in self._known(measurements):
            value = m.value
            if isinstance(value, np.ndarray) and value.shape == (sizes.get(m.sensor_id),):
                continue  # a vector of its sensor's size: nothing below would raise
            validate_measurement(m, self.sensors)
            if not isinstance(value, np.ndarray) or value.ndim != 1:
                raise MeasurementError(
                    invalid(
                        f"value.shape (sensor {m.sensor_id!r}, time={m.time})",
                        getattr(m.value, "shape", type(m.value).__name__),
                        "(m,): one report, a vector (the tracker takes no batched Monte Carlo"
                        " runs, and gates every report)",
                    )
                )

    def _check_scan(
        self,
        state: TrackerState,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None,
        scanned: Collection[str] | None = None,
    ) -> float:
        """Raise before any work when the scan cannot be processed; return the time as float."""
        try:
            t = float(time)
        except (TypeError, ValueError):
            raise MeasurementError(invalid("time", time, "a finite number (seconds)")) from None
        if not math.isfinite(t):
            raise MeasurementError(invalid("time", time, "a finite number (seconds)"))
        if state.time is not None and t < state.time - TIME_TOLERANCE:
            raise MeasurementError(
                f"scan time={t} comes before the last scan's time={state.time}: scans must not go "
                "back in time (run(..., order='reorder') sorts a recording)"
            )
        self._check_measurements(measurements)
        for sid in scanned or ():
            if sid not in self.sensors:
                raise UnknownSensorError(
                    invalid("scanned", sid, f"one of the sensors {sorted(self.sensors)}")
                )
        if rng is None and callable(getattr(self.filter, "initialize", None)):
            raise ConfigError(
                invalid("rng", rng, f"a numpy Generator: {type(self.filter).__name__} draws")
            )
        return t

    def _screen(
        self,
        stats: TrackerStats,
        measurements: Sequence[Measurement],
        scanned: Collection[str] | None,
    ) -> tuple[list[int], list[str], TrackerStats]:
        """The usable measurements (indices), the sensors that looked, in processing order, and
        the stats with this scan counted. A measurement with a NaN or infinite value or
        covariance is skipped and counted; its sensor counts as having looked only when it is in
        ``scanned`` or sent a usable measurement too (a corrupt report is no evidence of a miss)."""
        known = [j for j, m in enumerate(measurements) if m.sensor_id in self.sensors]
        unknown = len(measurements) - len(known)
        usable = (
            known
            if _all_finite([measurements[j] for j in known])
            else [j for j in known if _usable(measurements[j])]
        )
        skipped = len(measurements) - unknown - len(usable)
        reporting = list(dict.fromkeys(measurements[j].sensor_id for j in usable))
        silent = {m.sensor_id for m in measurements} - set(reporting)
        rest = [s for s in self.sensors if s not in silent] if scanned is None else scanned
        order = reporting + [s for s in self.sensors if s in rest and s not in reporting]
        stats = stats.add(
            scans=1,
            empty_scans=not usable,
            measurements=len(measurements),
            skipped_nonfinite=skipped,
            skipped_unknown_sensor=unknown,
        )
        return usable, order, stats

    def step(
        self,
        state: TrackerState,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
        *,
        scanned: Collection[str] | None = None,
    ) -> TrackerState:
        """The state after the scan at ``time`` with ``measurements`` (module docstring).

        ``scanned``: the sensors that looked in this scan, default all (a sensor that looked
        and reported nothing misses every track). Sensors with usable measurements always
        count; they are processed in the order of their first measurement, then the silent
        ones. Measurements with NaN or infinite values are skipped and counted in
        ``state.stats`` (a sensor that sent only such reports did not look); so are those of
        unknown sensors when the tracker was built with ``unknown_sensors="skip"``. Raises
        before any work on an unknown sensor (by default), a value of the wrong size, or a time
        before the last scan's (the message names both times).
        """
        t = self._check_scan(state, time, measurements, rng, scanned)
        usable, order, stats = self._screen(state.stats, measurements, scanned)
        predicted, stacked = self._predict(state.tracks, t, rng)
        tracks = {tr.id: tr for tr in predicted}
        records = {i: _ScanRecord() for i in tracks}
        births = _Births(state.next_id, state.initiator_state)
        for sid in order:
            cols = [j for j in usable if measurements[j].sensor_id == sid]
            if sid in self.birth_only_sensors:
                cols = self._outside_gates(tracks.values(), measurements, cols, sid)
            else:
                shared = self._score_once(tracks, measurements, cols, sid, rng, stacked)
                stacked = None  # the tracks change below: the next sensor stacks them anew
                for confirmed in (True, False):
                    ids = [i for i, tr in tracks.items() if tr.confirmed == confirmed]
                    cols = self._associate(
                        tracks, records, ids, measurements, cols, sid, rng, shared
                    )
            for tr, j in self._births(births, t, sid, [measurements[j] for j in cols], rng):
                tracks[tr.id] = tr
                records[tr.id] = _ScanRecord(True, [] if j is None else [(cols[j], 1.0)])
        stats = stats.add(births=births.next_id - state.next_id)
        looked = any(sid not in self.birth_only_sensors for sid in order)
        survivors, stats = self._settle(tracks, records, t, state.next_id, looked, stats)
        return TrackerState(survivors, t, births.next_id, stats, births.initiator_state)

    def _settle(
        self,
        tracks: Mapping[int, LiveTrack],
        records: Mapping[int, _ScanRecord],
        time: float,
        first_new: int,
        looked: bool,
        stats: TrackerStats,
    ) -> tuple[tuple[LiveTrack, ...], TrackerStats]:
        """After a scan: count each track's hit or miss (none when no sensor looked), confirm or
        drop tentative tracks (``initiator.status``), delete confirmed ones (``deleter``)."""
        survivors = []
        dropped = confirmed = deleted = 0  # added to the stats once, after the loop
        for i, tr in tracks.items():
            if looked or i >= first_new:
                tr = self._count(tr, records[i], time, newborn=i >= first_new)
            else:  # no sensor looked: neither hit nor miss, and no measurement this scan
                tr = tr.evolve(measurements=(), probabilities=())
            if not tr.confirmed:
                status = self.initiator.status(tr)
                if status == "dropped":
                    dropped += 1
                    continue
                tr = tr.evolve(confirmed=status == "confirmed")
                confirmed += tr.confirmed
            if tr.confirmed and self.deleter.should_delete(tr):
                deleted += 1
                continue
            survivors.append(tr)
        stats = stats.add(dropped=dropped, confirmed=confirmed, deleted=deleted)
        return tuple(survivors), stats

    def _predict(
        self, tracks: Sequence[LiveTrack], time: float, rng: np.random.Generator | None
    ) -> tuple[list[LiveTrack], Gaussian | None]:
        """The tracks predicted to ``time`` (those of one time in one batched call,
        :func:`~fusetrack.association.predict_stacked`), their existence with ``P_S``; and
        the predictions as one batched Gaussian when one call predicted them all (else None)."""
        out = list(tracks)
        due: dict[float, list[int]] = {}
        for k, tr in enumerate(tracks):
            if time - tr.time > TIME_TOLERANCE:
                due.setdefault(tr.time, []).append(k)
        stacked = None
        for t0, ks in due.items():
            before = [tracks[k].belief for k in ks]
            stacked = predict_stacked(self.filter, before, time - t0, rng)
            beliefs = (
                stacked.unstack()
                if stacked is not None
                else [self.filter.predict(b, time - t0, rng) for b in before]
            )
            for k, belief in zip(ks, beliefs, strict=True):
                out[k] = tracks[k].evolve(
                    belief=belief,
                    time=time,
                    existence=predict_existence(tracks[k].existence, self.survival_probability),
                )
        all_in_one = len(due) == 1 and len(next(iter(due.values()))) == len(tracks)
        return out, stacked if all_in_one else None

    def _births(
        self,
        births: _Births,
        time: float,
        sensor_id: str,
        leftover: Sequence[Measurement],
        rng: np.random.Generator | None,
    ) -> list[tuple[LiveTrack, int | None]]:
        """New tentative tracks from one sensor's ``leftover`` measurements, with the index of
        the measurement each used (None: none in particular); ``births`` advances. A
        scan-level initiator (with ``births(state, time, sensor_id, measurements, rng)``, e.g.
        :class:`~fusetrack.tracking.PHDInitiator`) sees them all at once, any other each
        alone (``initiator.birth(measurement)``)."""
        scan_level = getattr(self.initiator, "births", None)
        if callable(scan_level):
            births.initiator_state, started = scan_level(
                births.initiator_state, time, sensor_id, leftover, rng
            )
        else:
            started = [(self.initiator.birth(m), j) for j, m in enumerate(leftover)]
        out = []
        initialize = getattr(self.filter, "initialize", None)
        for belief, j in started:
            if belief is None:
                continue
            if isinstance(belief, Gaussian) and callable(initialize):
                belief = initialize(belief, rng)
            track = LiveTrack(
                births.next_id, belief, time, time, time, existence=self.birth_existence
            )
            out.append((track, j))
            births.next_id += 1
        return out

    def _associate(
        self,
        tracks: dict[int, LiveTrack],
        records: dict[int, _ScanRecord],
        ids: list[int],
        measurements: Sequence[Measurement],
        cols: list[int],
        sensor_id: str,
        rng: np.random.Generator | None,
        shared: _SharedScores | None = None,
    ) -> list[int]:
        """Associate the tracks ``ids`` with the measurements ``cols`` (all of ``sensor_id``),
        update them in ``tracks`` and ``records``; return the columns left unassociated. Their
        scores come from ``shared`` when given (:meth:`_score_once`), else are computed here."""
        if not ids:
            return cols
        p_d = self.p_detect[sensor_id]
        chosen = [measurements[j] for j in cols]
        before = [tracks[i] for i in ids]
        prior = None
        if shared is None:
            scores, posteriors = self._score(ids, [tr.belief for tr in before], chosen, p_d, rng)
        else:
            prior, scores, posteriors = shared.restrict(ids, cols)
        weights, left = self._associate_gated(scores, rng)
        beliefs = self._combine(before, weights, posteriors, chosen, rng, prior)
        existence = update_existences(
            [tr.existence for tr in before],
            p_d * self.gate_probability,
            _likelihood_ratio_sums(scores, weights),
        )
        for i, tr, belief, r in zip(ids, before, beliefs, existence.tolist(), strict=True):
            tracks[i] = tr.evolve(belief=belief, existence=r)
        used_rows, used_cols = np.nonzero(weights[:, :-1])
        used: dict[int, list[tuple[int, float]]] = {}
        for row, k, w in zip(
            used_rows.tolist(), used_cols.tolist(), weights[used_rows, used_cols].tolist()
        ):
            used.setdefault(row, []).append((cols[k], w))
        for row, pairs in used.items():  # the tracks that took measurements
            record = records[ids[row]]
            record.used.extend(pairs)
            record.detected |= sum(p for _, p in pairs) >= 0.5
        return [cols[k] for k in left]

    def _outside_gates(
        self,
        tracks: Iterable[LiveTrack],
        measurements: Sequence[Measurement],
        cols: list[int],
        sensor_id: str,
    ) -> list[int]:
        """The measurements ``cols`` (of a birth-only sensor) outside every track's
        ``gate_probability`` gate (:func:`~fusetrack.association.mahalanobis_squared`)."""
        beliefs = [tr.belief for tr in tracks]
        if not beliefs or not cols:
            return cols
        sensor = self.sensors[sensor_id]
        d2 = mahalanobis_squared(sensor, beliefs, [measurements[j] for j in cols])
        inside = d2 <= gate_threshold(self.gate_probability, sensor.dim)
        return [cols[k] for k in np.flatnonzero(~inside.any(axis=0)).tolist()]

    def _score_once(
        self,
        tracks: Mapping[int, LiveTrack],
        measurements: Sequence[Measurement],
        cols: list[int],
        sensor_id: str,
        rng: np.random.Generator | None,
        stacked: Gaussian | None = None,
    ) -> _SharedScores | None:
        """All the tracks scored against all of one sensor's measurements ``cols`` in one
        batch, for the confirmed and then the tentative tracks' association to take their
        blocks from (a pair's score and posterior do not depend on the other pairs). Only for
        a batched Gaussian filter (:func:`~fusetrack.association.batchable`, deterministic);
        None for any other, whose pairs are scored pass by pass (a random filter draws only
        for the pairs it is given). ``stacked``: the tracks' beliefs as one batch, if at hand."""
        if not tracks or not cols:
            return None
        if stacked is None:
            beliefs = [tr.belief for tr in tracks.values()]
            if not batchable(self.filter, beliefs):
                return None
            stacked = stack_gaussians(beliefs)
        chosen = [measurements[j] for j in cols]
        ids = list(tracks)
        scores, posteriors = self._score(ids, stacked, chosen, self.p_detect[sensor_id], rng)
        return _SharedScores(ids, cols, stacked, scores, posteriors)

    def _combine(
        self,
        tracks: Sequence[LiveTrack],
        weights: np.ndarray,
        posteriors: Mapping[tuple[int, int], Any],
        chosen: Sequence[Measurement],
        rng: np.random.Generator | None,
        prior: Gaussian | None = None,
    ) -> list[Any]:
        """Each track's belief after its hypotheses (row ``weights[row]``): the posterior of
        each measurement (the prediction when missed) combined (:mod:`.mixing`). Gaussian
        tracks whose pairs were updated in one batch are combined in one array pass
        (:func:`.mixing.combine_stacked`; ``prior``: their beliefs stacked, if at hand), the
        others one by one."""
        if isinstance(posteriors, PairPosteriors):
            outside = weights[:, :-1] > 0  # weight on a pair outside the gate: one by one
            outside[posteriors.rows, posteriors.cols] = False
            if not outside.any():
                if prior is None:
                    prior = stack_gaussians([tr.belief for tr in tracks])
                return combine_stacked(prior, posteriors, weights).unstack()
        out = []
        for row, tr in enumerate(tracks):
            ks = np.flatnonzero(weights[row]).tolist()  # measurements, then missed (the last)
            beliefs = []
            for k in ks:
                post = None if k == len(chosen) else posteriors.get((row, k))
                if post is None and k < len(chosen):  # the associator chose outside the gate
                    post = self.filter.update(tr.belief, [chosen[k]], rng)
                beliefs.append(tr.belief if post is None else post)
            out.append(combine_hypotheses(beliefs, weights[row, ks].tolist()))
        return out

    def _associate_gated(
        self, scores: ScanLikelihoods, rng: np.random.Generator | None
    ) -> tuple[np.ndarray, list[int]]:
        """``(weights (T, M + 1), unassociated columns)``: each track's normalised hypothesis
        weights (last column: missed) from the associator on the gated block only: the tracks
        with a measurement in their gate against the measurements in some gate. The others
        drop out of every joint event's score as constant factors (a track without a gated
        measurement is missed, a measurement in no gate is clutter; Bar-Shalom, Daum & Huang
        2009's validation matrix), so the answer is the same, and a scan of thousands of false
        alarms far from the tracks costs the associator nothing. An associator with
        ``association_weights`` answers with the matrix, any other with an
        :class:`~fusetrack.association.Association` (:func:`hypothesis_weights`)."""
        t, m = scores.shape
        gated = np.isfinite(scores.log_likelihood)
        rows = np.flatnonzero(gated.any(axis=1))
        cols = np.flatnonzero(gated.any(axis=0))
        weights = np.zeros((t, m + 1))
        weights[:, m] = 1.0
        if not rows.size:
            return weights, list(range(m))
        block = ScanLikelihoods(
            tuple(scores.track_ids[r] for r in rows),
            scores.log_likelihood[np.ix_(rows, cols)],
            scores.log_missed[rows],
            scores.log_clutter[cols],
        )
        as_matrix = getattr(self.associator, "association_weights", None)
        if callable(as_matrix):
            answer = as_matrix(block, rng)
            inner, left = (
                _checked_weights(self.associator, answer, block.shape),
                answer.unassociated,
            )
        else:
            association = self.associator.associate(block, rng)
            _check_association(self.associator, association, cols.size)
            inner = hypothesis_weights(association, block.track_ids, cols.size)
            left = association.unassociated
        weights[np.ix_(rows, np.append(cols, m))] = _normalised_rows(inner)
        col = cols.tolist()
        in_no_gate = set(range(m)) - set(col)
        return weights, sorted(in_no_gate | {col[k] for k in left})

    def _score(
        self,
        ids: Sequence[int],
        beliefs: Sequence[Any] | Gaussian,
        chosen: Sequence[Measurement],
        p_detect: float,
        rng: np.random.Generator | None,
    ) -> tuple[ScanLikelihoods, Mapping[tuple[int, int], Any]]:
        """:func:`~fusetrack.association.scan_likelihoods` of ``beliefs`` (rows ``ids``) against
        one sensor's measurements ``chosen``, with the gated pairs' posteriors."""
        return scan_likelihoods(
            ids,
            beliefs,
            chosen,
            self.sensors,
            self.filter,
            p_detect,
            self.clutter_density,
            self.gate_probability,
            rng,
            keep_posteriors=True,
            validated=True,  # step: _check_measurements and _screen did it
        )

    @staticmethod
    def _count(track: LiveTrack, record: _ScanRecord, time: float, newborn: bool) -> LiveTrack:
        """The track's hit and miss counts after the scan (a new track's birth is its first hit)."""
        used = tuple([j for j, _ in record.used])
        probabilities = tuple([p for _, p in record.used])
        if newborn:
            return track.evolve(measurements=used, probabilities=probabilities)
        if record.detected:
            return track.evolve(
                scans=track.scans + 1,
                hits=track.hits + 1,
                misses=0,
                last_hit=time,
                measurements=used,
                probabilities=probabilities,
            )
        return track.evolve(
            scans=track.scans + 1,
            misses=track.misses + 1,
            measurements=used,
            probabilities=probabilities,
        )

    # -- a whole recording -----------------------------------------------------------------------

    def run(
        self,
        measurements: Iterable[Measurement | tuple[Any, ...]],
        rng: np.random.Generator | None = None,
        *,
        times: ArrayLike | None = None,
        order: Literal["reject", "reorder"] = "reject",
    ) -> list[Track]:
        """Track over a whole recording: one scan per distinct measurement time (within 1e-9 s,
        :func:`~fusetrack.core.group_by_time`) plus one empty scan at each of ``times`` where
        no measurement falls (every sensor looked and saw nothing).

        Returns the tracks that were ever confirmed, by id: ``times`` from the birth scan to the
        last scan alive, ``means``/``covariances`` after each scan, and ``info`` with
        ``"measurements"`` (per scan, the indices into ``measurements`` the track used),
        ``"probabilities"`` (their association probabilities), ``"existence"`` ``(T,)``,
        ``"confirmed"`` ``(T,)`` bool, and ``"deleted"`` (the time of the first scan without it,
        or None when it was alive at the end). :meth:`run_with_state` also returns the final
        state (its ``stats``). Out-of-order timestamps raise (naming both times) unless
        ``order="reorder"``.
        """
        return self.run_with_state(measurements, rng, times=times, order=order)[0]

    def run_with_state(
        self,
        measurements: Iterable[Measurement | tuple[Any, ...]],
        rng: np.random.Generator | None = None,
        *,
        times: ArrayLike | None = None,
        order: Literal["reject", "reorder"] = "reject",
    ) -> tuple[list[Track], TrackerState]:
        """:meth:`run`, and the state after the last scan (``state.stats``: what was skipped)."""
        ms = as_measurements(measurements)
        if order not in ("reject", "reorder"):
            raise ConfigError(invalid("order", order, "'reject' or 'reorder'"))
        index = (
            sorted(range(len(ms)), key=lambda k: ms[k].time)
            if order == "reorder"
            else range(len(ms))
        )
        ordered = order_by_time([ms[k] for k in index], "reject")
        scans = self._scans(ordered, list(index), times)
        state = self.initial_state()
        self._check_measurements(ordered)  # before any work
        history: dict[int, _History] = {}  # tracks alive, and ended ones that were confirmed
        alive: set[int] = set()
        for t, idx in scans:
            state = self.step(state, t, [ms[k] for k in idx], rng)
            for tr in state.tracks:
                history.setdefault(tr.id, _History()).add(self.filter, tr, t, idx)
            now = {tr.id for tr in state.tracks}
            for i in alive - now:
                if any(history[i].confirmed):
                    history[i].deleted = t
                else:  # a tentative track dropped: never reported
                    del history[i]
            alive = now
        tracks = [h.track(i) for i, h in sorted(history.items()) if any(h.confirmed)]
        return tracks, state

    @staticmethod
    def _scans(
        ordered: list[Measurement], index: list[int], times: ArrayLike | None
    ) -> list[tuple[float, list[int]]]:
        """``(time, indices into the original measurements)`` per scan, with empty scans at ``times``."""
        scans: list[tuple[float, list[int]]] = []
        k = 0
        for t, group in group_by_time(ordered, TIME_TOLERANCE):
            scans.append((t, index[k : k + len(group)]))
            k += len(group)
        if times is not None:
            extra = np.atleast_1d(np.asarray(times, dtype=float))
            if extra.ndim != 1 or not np.all(np.isfinite(extra)):
                raise ConfigError(
                    invalid("times", times, "a 1-D sequence of finite times (seconds)")
                )
            have = np.array([t for t, _ in scans])
            for t in np.unique(extra):
                if not have.size or np.min(np.abs(have - t)) > TIME_TOLERANCE:
                    scans.append((float(t), []))
            scans.sort(key=lambda s: s[0])
        return scans


def _likelihood_ratio_sums(scores: ScanLikelihoods, weights: np.ndarray) -> np.ndarray:
    """``(T,)``: each track's ``sum_j l_j`` over the measurements its hypotheses used
    (:mod:`.existence`; ``l_j = exp(log P_D p(z_j | track) - log kappa_j)``, 0 outside the gate)."""
    rows, cols = np.nonzero(weights[:, :-1])
    ratios = np.exp(scores.log_likelihood[rows, cols] - scores.log_clutter[cols])
    return np.bincount(rows, weights=ratios, minlength=weights.shape[0])


@dataclass
class _SharedScores:
    """One sensor's scores of all the tracks ``ids`` against its measurements ``cols``
    (:meth:`MultiTargetTracker._score_once`)."""

    ids: list[int]
    cols: list[int]
    prior: Gaussian  # the tracks' beliefs, a row per track
    scores: ScanLikelihoods
    posteriors: Mapping[tuple[int, int], Any]

    def restrict(
        self, ids: Sequence[int], cols: Sequence[int]
    ) -> tuple[Gaussian, ScanLikelihoods, Mapping[tuple[int, int], Any]]:
        """The beliefs, scores and posteriors of the tracks ``ids`` against the measurements
        ``cols`` (both in the order of ``self.ids`` and ``self.cols``)."""
        row_of = {i: r for r, i in enumerate(self.ids)}
        col_of = {j: c for c, j in enumerate(self.cols)}
        rows = [row_of[i] for i in ids]
        ks = [col_of[j] for j in cols]
        s = self.scores
        scores = ScanLikelihoods(
            tuple(s.track_ids[r] for r in rows),
            s.log_likelihood[np.ix_(rows, ks)],
            s.log_missed[rows],
            s.log_clutter[ks],
        )
        assert isinstance(self.posteriors, PairPosteriors)  # _score_once: a batched filter
        prior = Gaussian(self.prior.mean[rows], self.prior.cov[rows])
        return prior, scores, self.posteriors.restrict(rows, ks, s.shape)


@dataclass
class _History:
    """One track's estimates scan by scan, gathered by :meth:`MultiTargetTracker.run`."""

    times: list[float] = field(default_factory=list)
    means: list[np.ndarray] = field(default_factory=list)
    covs: list[np.ndarray] = field(default_factory=list)
    used: list[tuple[int, ...]] = field(default_factory=list)
    probabilities: list[tuple[float, ...]] = field(default_factory=list)
    existence: list[float] = field(default_factory=list)
    confirmed: list[bool] = field(default_factory=list)
    deleted: float | None = None

    def add(self, filt: Any, track: LiveTrack, time: float, scan_index: Sequence[int]) -> None:
        estimate = getattr(filt, "estimate", None)
        summary = estimate(track.belief) if callable(estimate) else track.belief
        self.times.append(time)
        self.means.append(np.asarray(summary.mean, float))
        self.covs.append(np.asarray(summary.cov, float))
        self.used.append(tuple(scan_index[j] for j in track.measurements))
        self.probabilities.append(track.probabilities)
        self.existence.append(track.existence)
        self.confirmed.append(track.confirmed)

    def track(self, track_id: int) -> Track:
        info = {
            "measurements": tuple(self.used),
            "probabilities": tuple(self.probabilities),
            "existence": np.array(self.existence),
            "confirmed": np.array(self.confirmed),
            "deleted": self.deleted,
        }
        return Track(
            np.array(self.times),
            np.stack(self.means),
            np.stack(self.covs),
            label=f"track {track_id}",
            info=info,
            id=track_id,
        )
