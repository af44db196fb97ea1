"""Online MCMCDA behind the trackers' interface: :class:`~fusetrack.association.MCMCDA` (Oh,
Russell & Sastry 2009) fed with :class:`~fusetrack.core.Measurement` values, with
``initial_state / step / run`` returning live tracks and :class:`~fusetrack.core.Track` values
with persistent ids, like :class:`~fusetrack.tracking.MultiTargetTracker`, so a user (or the
live node) can swap methods.

MCMCDA works on 2-D positions at a fixed step ``config.dt`` with its own constant-velocity
model (state ``[x, y, vx, vy]``). So each measurement must come from a *position-like* sensor:
a linear sensor ``z = H x + c + v`` (a :class:`~fusetrack.sensors.PositionFix`, a
:class:`~fusetrack.sensors.LinearGaussianSensor` on the position) of a ``[x, y, vx, vy]``
state that determines exactly the two position components; its position is the inverse
``H_o^+ (z - c)`` (as :class:`~fusetrack.tracking.InverseMeasurementPrior`). Scan times must lie
on the grid ``t_0 + k dt`` of the first scan ``t_0``; steps without a scan are empty steps
(every target missed).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from ..association import MCMCDA, AssociationState, MCMCDAConfig
from ..core import (
    ConfigError,
    Gaussian,
    Measurement,
    MeasurementError,
    SensorModel,
    Track,
    as_measurements,
    group_by_time,
    invalid,
    order_by_time,
)
from ..filters import as_sensor_map, validate_measurement
from .initiators import _Inverse, _invert_linear
from .state import LiveTrack, TrackerStats

Array = NDArray[np.float64]
GRID_TOLERANCE = 1e-6  # a scan time within this fraction of dt of a grid point is on it


@dataclass(frozen=True, eq=False)
class MCMCDATrackerState:
    """What :class:`MCMCDATracker` carries between scans: the MCMCDA ``association`` state,
    the current ``tracks`` (one :class:`LiveTrack` per track of the window's best hypothesis,
    all confirmed), the last scan ``time`` and the first one ``start`` (step 0), ``stats``, and
    ``scan_index``: per step, the scan's usable measurement indices in observation order (to
    name each track's measurements; empty unless the tracker keeps its history)."""

    association: AssociationState = field(default_factory=AssociationState)
    tracks: tuple[LiveTrack, ...] = ()
    time: float | None = None
    start: float | None = None
    stats: TrackerStats = field(default_factory=TrackerStats)
    scan_index: tuple[tuple[int, ...], ...] = ()

    @property
    def confirmed(self) -> tuple[LiveTrack, ...]:
        return self.tracks

    @property
    def next_id(self) -> int:
        return self.association.next_id


def _position_inverse(sensor: SensorModel) -> _Inverse:
    """The inverse of a sensor that sees exactly the position of ``[x, y, vx, vy]``."""
    valid = "a position-like sensor of the state [x, y, vx, vy]: linear, determining x and y"
    try:
        inverse = _invert_linear(sensor, 4)
    except ConfigError as err:
        raise ConfigError(invalid("sensors", sensor.sensor_id, f"{valid} ({err})")) from err
    if inverse.observed.tolist() != [0, 1]:
        raise ConfigError(
            invalid(
                "sensors",
                sensor.sensor_id,
                f"{valid} only (this one sees components {inverse.observed.tolist()})",
            )
        )
    return inverse


class MCMCDATracker:
    """Online MCMCDA as a tracker (module docstring).

    Parameters
    ----------
    sensors:
        the position-like sensor models (mapping or sequence by ``sensor_id``).
    mcmcda:
        an :class:`~fusetrack.association.MCMCDA` or its :class:`MCMCDAConfig` (default
        config: ``dt`` 0.25 s, a 35 m x 20 m field).
    unknown_sensors:
        ``"raise"`` (default) or ``"skip"`` (counted in ``stats.skipped_unknown_sensor``).
    keep_history:
        True (default): keep every step's observations, so that :meth:`run` (and
        :meth:`tracks`) can give whole tracks; False for a tracker that runs indefinitely
        (:meth:`~fusetrack.association.MCMCDA.forget_past` after every step; only
        ``state.tracks`` then).
    """

    filter: Any = None
    """No filter object: the beliefs are :class:`~fusetrack.core.Gaussian` values (the live
    node reads ``tracker.filter`` for an ``estimate``; there is none to apply)."""

    def __init__(
        self,
        sensors: Mapping[str, SensorModel] | Sequence[SensorModel],
        mcmcda: MCMCDA | MCMCDAConfig | None = None,
        *,
        unknown_sensors: Literal["raise", "skip"] = "raise",
        keep_history: bool = True,
    ) -> None:
        self.sensors = as_sensor_map(sensors)
        if not self.sensors:
            raise ConfigError(invalid("sensors", sensors, "at least one position-like sensor"))
        self.inverses = {sid: _position_inverse(s) for sid, s in self.sensors.items()}
        if mcmcda is None or isinstance(mcmcda, MCMCDAConfig):
            mcmcda = MCMCDA(mcmcda or MCMCDAConfig())
        if not isinstance(mcmcda, MCMCDA):
            raise ConfigError(invalid("mcmcda", mcmcda, "an MCMCDA or an MCMCDAConfig"))
        self.mcmcda = mcmcda
        if unknown_sensors not in ("raise", "skip"):
            raise ConfigError(invalid("unknown_sensors", unknown_sensors, "'raise' or 'skip'"))
        self.unknown_sensors = unknown_sensors
        self.keep_history = bool(keep_history)

    def __repr__(self) -> str:
        return f"MCMCDATracker(sensors={sorted(self.sensors)}, config={self.mcmcda.config!r})"

    @property
    def dt(self) -> float:
        return float(self.mcmcda.config.dt)

    def initial_state(self) -> MCMCDATrackerState:
        """No observations, no tracks, no scan yet."""
        return MCMCDATrackerState(self.mcmcda.initial_state())

    # -- one scan ------------------------------------------------------------------------------

    def _check(self, state: MCMCDATrackerState, time: float, measurements: Sequence[Any]) -> int:
        """The number of steps this scan advances (>= 1), or a clear error before any work."""
        try:
            t = float(time)
        except (TypeError, ValueError):
            raise MeasurementError(invalid("time", time, "a finite number (seconds)")) from None
        if not math.isfinite(t):
            raise MeasurementError(invalid("time", time, "a finite number (seconds)"))
        for m in measurements:
            if not isinstance(m, Measurement):
                raise MeasurementError(invalid("measurements", m, "Measurement objects"))
            if m.sensor_id in self.sensors or self.unknown_sensors == "raise":
                validate_measurement(m, self.sensors)
                if not isinstance(m.value, np.ndarray) or m.value.ndim != 1:
                    raise MeasurementError(
                        invalid(
                            f"value.shape (sensor {m.sensor_id!r}, time={m.time})",
                            getattr(m.value, "shape", type(m.value).__name__),
                            "(m,): one report, a vector",
                        )
                    )
        if state.time is None or state.start is None:
            return 1
        if t <= state.time + GRID_TOLERANCE * self.dt:
            raise MeasurementError(
                f"scan time={t} does not come after the last scan's time={state.time}: MCMCDA"
                f" takes one scan per step of dt={self.dt} s, in time order"
            )
        steps = (t - state.start) / self.dt
        if abs(steps - round(steps)) > GRID_TOLERANCE:
            raise MeasurementError(
                invalid(
                    "time",
                    t,
                    f"a scan time on MCMCDA's grid {state.start} + k * {self.dt} (dt = config.dt)",
                )
            )
        return round(steps) - (state.association.steps - 1)

    def _positions(
        self, measurements: Sequence[Measurement]
    ) -> tuple[Array, Array | None, tuple[int, ...], dict[str, int]]:
        """The usable measurements' positions ``(n, 2)``, their covariances ``(n, 2, 2)``
        (None when no measurement carries one: ``config.obs_std`` for all; otherwise
        ``Measurement.covariance`` mapped through the sensor's inverse, ``obs_std² I`` for those
        without), their indices, and skip counts."""
        rows, covs, index = [], [], []
        iso = self.mcmcda.config.obs_std**2 * np.eye(2)
        unknown = nonfinite = 0
        for j, m in enumerate(measurements):
            inverse = self.inverses.get(m.sensor_id)
            if inverse is None:
                unknown += 1
                continue
            value = np.asarray(m.value, float)
            if not np.all(np.isfinite(value)):
                nonfinite += 1
                continue
            rows.append(inverse.pinv @ (value - inverse.offset))
            c = m.covariance
            covs.append(iso if c is None else inverse.pinv @ np.asarray(c, float) @ inverse.pinv.T)
            index.append(j)
        counts = {"skipped_unknown_sensor": unknown, "skipped_nonfinite": nonfinite}
        carried = any(measurements[j].covariance is not None for j in index)
        cov = np.array(covs, float).reshape(-1, 2, 2) if carried else None
        return np.array(rows, float).reshape(-1, 2), cov, tuple(index), counts

    def step(
        self,
        state: MCMCDATrackerState,
        time: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
        *,
        scanned: Any = None,
    ) -> MCMCDATrackerState:
        """The state after the scan at ``time``: one MCMCDA step (``n_mc`` moves over the
        window) on the scan's positions, after empty steps for any grid points skipped since
        the last scan. ``rng`` is required (the chain draws); ``scanned`` is accepted for
        interface compatibility (MCMCDA's ``p_detect`` covers every step). Measurements with
        NaN values, and of unknown sensors with ``unknown_sensors="skip"``, are skipped and
        counted in ``state.stats``."""
        if not isinstance(rng, np.random.Generator):
            raise ConfigError(invalid("rng", rng, "a numpy Generator: MCMCDA's chain draws"))
        advance = self._check(state, time, measurements)
        t = float(time)
        y, cov, index, counts = self._positions(measurements)
        association, scan_index = state.association, state.scan_index
        for _ in range(advance - 1):  # grid points without a scan: every target missed
            association = self._advance(association, np.zeros((0, 2)), rng)
            scan_index = (*scan_index, ()) if self.keep_history else ()
        association = self._advance(association, y, rng, cov)
        scan_index = (*scan_index, index) if self.keep_history else ()
        stats = state.stats.add(
            scans=1,
            empty_scans=not len(y),
            measurements=len(measurements),
            births=association.next_id - state.association.next_id,
            **counts,
        )
        start = t if state.start is None else state.start
        tracks = self._live(association, start, index)
        return MCMCDATrackerState(association, tracks, t, start, stats, scan_index)

    def _advance(
        self,
        association: AssociationState,
        y: Array,
        rng: np.random.Generator,
        cov: Array | None = None,
    ) -> AssociationState:
        after = self.mcmcda.step(association, y, rng, cov)
        return after if self.keep_history else self.mcmcda.forget_past(after)

    def _live(
        self, association: AssociationState, start: float, index: Sequence[int]
    ) -> tuple[LiveTrack, ...]:
        """The best hypothesis' tracks now (:meth:`MCMCDA.current_tracks`), as live tracks."""
        now = association.steps - 1
        estimates = self.mcmcda.current_tracks(association)
        out = []
        for key in association.best:
            ident = association.ids.get(key)
            if ident not in estimates:
                continue
            x, p = estimates[ident]
            committed = association.committed.get(ident, {})
            first = min([*committed, key[0][0]])
            last = key[-1][0]
            used = tuple(index[o[1]] for o in key if o[0] == now)
            out.append(
                LiveTrack(
                    ident,
                    Gaussian(x, p),
                    start + now * self.dt,
                    born=start + first * self.dt,
                    last_hit=start + last * self.dt,
                    confirmed=True,
                    scans=now - first + 1,
                    hits=len(committed) + len(key),
                    misses=now - last,
                    existence=1.0,
                    measurements=used,
                    probabilities=(1.0,) * len(used),
                )
            )
        return tuple(sorted(out, key=lambda tr: tr.id))

    # -- a whole recording -----------------------------------------------------------------------

    def run(
        self,
        measurements: Iterable[Measurement | tuple[Any, ...]],
        rng: np.random.Generator | None = None,
        *,
        times: Any = None,
        order: Literal["reject", "reorder"] = "reject",
    ) -> list[Track]:
        """Track over a whole recording (one scan per distinct time, on the ``dt`` grid; the
        ``times`` argument is accepted for interface compatibility: skipped grid points are
        empty steps anyway). Returns the committed tracks (at least 2 observations) by id:
        ``times`` on the grid from the first to the last observation, ``means`` ``(T, 4)`` and
        ``covariances`` filtered through the track's observations (predictions at missed
        steps), ``info["measurements"]`` per step the indices into ``measurements`` it used."""
        return self.run_with_state(measurements, rng, order=order)[0]

    def run_with_state(
        self,
        measurements: Iterable[Measurement | tuple[Any, ...]],
        rng: np.random.Generator | None = None,
        *,
        order: Literal["reject", "reorder"] = "reject",
    ) -> tuple[list[Track], MCMCDATrackerState]:
        """:meth:`run`, and the state after the last scan."""
        if not self.keep_history:
            raise ConfigError(invalid("keep_history", False, "True to run a whole recording"))
        ms = as_measurements(measurements)
        if order not in ("reject", "reorder"):
            raise ConfigError(invalid("order", order, "'reject' or 'reorder'"))
        index = sorted(range(len(ms)), key=lambda k: ms[k].time) if order == "reorder" else None
        ordered = order_by_time(ms if index is None else [ms[k] for k in index], "reject")
        index = list(range(len(ms))) if index is None else index
        state = self.initial_state()
        self._check(state, 0.0, ordered)  # every measurement before any work
        k = 0
        scans = []
        for t, group in group_by_time(ordered, 1e-9):
            scans.append((t, index[k : k + len(group)]))
            k += len(group)
        for t, idx in scans:
            state = self.step(state, t, [ms[j] for j in idx], rng)
            *before, last = state.scan_index  # indices into this scan: into ``ms`` instead
            state = replace(state, scan_index=(*before, tuple(idx[j] for j in last)))
        return self.tracks(state), state

    def tracks(self, state: MCMCDATrackerState) -> list[Track]:
        """Every track of ``state`` with at least 2 observations, committed as if the data
        ended there (module docstring; needs ``keep_history``)."""
        if state.start is None:
            return []
        finished = self.mcmcda.finish(state.association)
        chain = self.mcmcda.sampler(finished)
        c = self.mcmcda.config
        f = np.eye(4)
        f[0, 2] = f[1, 3] = c.dt
        g = np.array([[c.dt**2 / 2, 0], [0, c.dt**2 / 2], [c.dt, 0], [0, c.dt]])
        q = c.accel_std**2 * g @ g.T
        out = []
        for ident, assoc in sorted(finished.committed.items()):
            if len(assoc) < 2:
                continue
            _, filtered = chain.kalman_full(tuple(sorted(assoc.items())))
            steps, means, covs = [], [], []
            for (t0, x, p), nxt in zip(filtered, [*filtered[1:], None]):
                for s in range(t0, t0 + 1 if nxt is None else nxt[0]):
                    steps.append(s)
                    means.append(x)
                    covs.append(0.5 * (p + p.T))
                    x, p = f @ x, f @ p @ f.T + q
            used = tuple(
                (state.scan_index[s][assoc[s]],) if s in assoc and state.scan_index else ()
                for s in steps
            )
            out.append(
                Track(
                    state.start + np.array(steps, float) * c.dt,
                    np.array(means),
                    np.array(covs),
                    label=f"track {ident}",
                    info={"measurements": used, "steps": np.array(steps)},
                    id=ident,
                )
            )
        return out
