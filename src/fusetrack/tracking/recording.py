"""A whole recording through any tracker: measurements grouped into scans by time, empty scans
where the sensors looked and saw nothing, and the confirmed tracks gathered by id into
:class:`~fusetrack.core.Track` values (:func:`run_tracker`). :class:`~.tracker.MultiTargetTracker`
keeps its own richer history (the measurements each track used); the random-finite-set trackers
(:class:`~.phd_tracker.PHDTracker`, :class:`~.pmb_tracker.PMBTracker`) run through this."""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..core import (
    ConfigError,
    Measurement,
    Track,
    as_measurements,
    group_by_time,
    invalid,
    order_by_time,
)
from .protocol import Tracker, belief_summary

TIME_TOLERANCE = 1e-9  # measurements closer in time than this form one scan


def scan_groups(
    ordered: list[Measurement], index: list[int], times: ArrayLike | None
) -> list[tuple[float, list[int]]]:
    """``(time, indices into the original measurements)`` per scan of the time-ordered
    ``ordered`` (``index[k]``: the original position of ``ordered[k]``), plus an empty scan at
    each of ``times`` where no measurement falls."""
    scans: list[tuple[float, list[int]]] = []
    k = 0
    for t, group in group_by_time(ordered, TIME_TOLERANCE):
        scans.append((t, index[k : k + len(group)]))
        k += len(group)
    if times is not None:
        extra = np.atleast_1d(np.asarray(times, dtype=float))
        if extra.ndim != 1 or not np.all(np.isfinite(extra)):
            raise ConfigError(invalid("times", times, "a 1-D sequence of finite times (seconds)"))
        have = np.array([t for t, _ in scans])
        for t in np.unique(extra):
            if not have.size or np.min(np.abs(have - t)) > TIME_TOLERANCE:
                scans.append((float(t), []))
        scans.sort(key=lambda s: s[0])
    return scans


def ordered_scans(
    measurements: Iterable[Measurement | tuple[Any, ...]],
    times: ArrayLike | None,
    order: Literal["reject", "reorder"],
) -> tuple[list[Measurement], list[tuple[float, list[int]]]]:
    """The measurements as :class:`~fusetrack.core.Measurement` values and their scans
    (:func:`scan_groups`); out-of-order timestamps raise (naming both times) unless
    ``order="reorder"``."""
    ms = as_measurements(measurements)
    if order not in ("reject", "reorder"):
        raise ConfigError(invalid("order", order, "'reject' or 'reorder'"))
    index = (
        sorted(range(len(ms)), key=lambda k: ms[k].time)
        if order == "reorder"
        else list(range(len(ms)))
    )
    ordered = order_by_time([ms[k] for k in index], "reject")
    return ms, scan_groups(ordered, index, times)


def with_silent_sensors(
    measurements: Sequence[Measurement],
    sensors: Mapping[str, Any],
    time: float,
    scanned: Collection[str] | None,
) -> list[Measurement]:
    """``measurements`` plus a NaN reading at ``time`` for every sensor in ``scanned`` (default
    all of ``sensors``) that sent nothing: it looked and saw nothing (the random-finite-set
    filters' missed-detection term)."""
    heard = {m.sensor_id for m in measurements}
    looked = sensors if scanned is None else scanned
    silent = [
        Measurement(time, sid, np.full(int(getattr(s, "value_size", s.dim)), np.nan))
        for sid, s in sensors.items()
        if sid in looked and sid not in heard
    ]
    return [*measurements, *silent]


def run_tracker(
    tracker: Tracker,
    measurements: Iterable[Measurement | tuple[Any, ...]],
    rng: np.random.Generator | None = None,
    *,
    times: ArrayLike | None = None,
    order: Literal["reject", "reorder"] = "reject",
    state: Any = None,
    observe: Callable[[float, Any], None] | None = None,
) -> list[Track]:
    """Step ``tracker`` scan by scan over a recording (from ``state``, default its
    ``initial_state()``) and return every track it ever confirmed, by id: the scans at which it
    was confirmed, its mean and covariance after each (``filter.estimate`` when the tracker's
    filter has one). ``observe(time, state)`` is called after each scan (e.g. to record a PHD's
    expected number of targets)."""
    ms, scans = ordered_scans(measurements, times, order)
    state = tracker.initial_state() if state is None else state
    history: dict[int, tuple[list[float], list[np.ndarray], list[np.ndarray]]] = {}
    for t, idx in scans:
        state = tracker.step(state, t, [ms[k] for k in idx], rng)
        for tr in state.confirmed:
            mean, cov = belief_summary(getattr(tracker, "filter", None), tr.belief)
            ts, means, covs = history.setdefault(int(tr.id), ([], [], []))
            ts.append(t)
            means.append(np.asarray(mean, float))
            covs.append(np.asarray(cov, float))
        if observe is not None:
            observe(t, state)
    return [
        Track(np.array(ts), np.stack(means), np.stack(covs), label=f"track {i}", id=i)
        for i, (ts, means, covs) in sorted(history.items())
    ]


def predict_and_update(
    filt: Any,
    belief: Any,
    last_time: float | None,
    time: float,
    measurements: Sequence[Measurement],
    sensors: Mapping[str, Any],
    scanned: Collection[str] | None,
    rng: np.random.Generator | None,
) -> Any:
    """One scan of a random-finite-set filter: predict from ``last_time`` (none: ``dt = 0``) to
    ``time``, then update with the scan's readings and a NaN reading for each silent sensor
    (:func:`with_silent_sensors`)."""
    dt = 0.0 if last_time is None else max(0.0, time - last_time)
    predicted = filt.predict(belief, dt, rng)
    return filt.update(predicted, with_silent_sensors(measurements, sensors, time, scanned), rng)


class RecordingRunner:
    """``run(measurements, ...)`` for a tracker: the whole recording through
    :func:`run_tracker`."""

    def run(
        self,
        measurements: Iterable[Measurement | tuple[Any, ...]],
        rng: np.random.Generator | None = None,
        *,
        times: ArrayLike | None = None,
        order: Literal["reject", "reorder"] = "reject",
        state: Any = None,
    ) -> list[Track]:
        """Track over a whole recording (:func:`run_tracker`): every track ever extracted, by
        id, at the scans it was extracted; ``state`` the state to start from (e.g. a prior
        intensity; default ``initial_state()``)."""
        return run_tracker(self, measurements, rng, times=times, order=order, state=state)  # type: ignore[arg-type]
