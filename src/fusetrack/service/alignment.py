"""Per-sensor ring buffers and the time alignment of readings to fusion ticks.

Ticks fall at ``t_k = start + k / rate`` (``k >= 1``; ``t_0 = start`` is the prior's time).
Tick ``k`` owns the readings in a window ``(end_{k-1}, end_k]``:

* ``alignment="all"``: ``end_k = t_k``; every reading in the window is fused, in time order
  (ties: sensor order of the config, then arrival), each at its own time;
* ``alignment="closest"``: ``end_k = t_k + period / 2``; per sensor the one reading closest to
  ``t_k`` is fused as if taken at ``t_k`` (ties: the earlier one); the others are *superseded*.

A tick fires when the clock has passed ``end_k + lag`` (:meth:`Aligner.due`), so readings up to
``lag`` seconds late still make it; a reading at or before the last fired window's end is *late*
and refused. Buffers are bounded: a full buffer drops its oldest reading (counted in
``dropped``), so a flooding sensor cannot exhaust memory or starve the others.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from ..core import ConfigError, invalid


@dataclass(frozen=True, eq=False)
class Reading:
    """An accepted reading: ``id`` is its arrival number (its row in the durable log)."""

    id: int
    sensor: str
    time: float
    value: np.ndarray
    covariance: np.ndarray | None = None


@dataclass
class SensorBuffer:
    """A bounded buffer of one sensor's unfused readings, kept in time order."""

    size: int
    items: list[Reading] = field(default_factory=list)
    dropped: int = 0

    def push(self, reading: Reading) -> None:
        bisect.insort(self.items, reading, key=lambda r: (r.time, r.id))
        if len(self.items) > self.size:
            del self.items[0]  # the oldest goes first
            self.dropped += 1

    def extend(self, readings: Sequence[Reading]) -> None:
        """:meth:`push` each of ``readings``: appended at once when they arrive in time order
        (the usual case), inserted one by one otherwise; then the oldest past ``size`` go."""
        items, last = self.items, self.items[-1].time if self.items else -math.inf
        for r in readings:
            if r.time < last:
                break
            last = r.time
        else:
            items.extend(readings)  # ids grow with arrival: (time, id) order holds
            readings = ()
        for r in readings:
            bisect.insort(items, r, key=lambda r: (r.time, r.id))
        excess = len(items) - self.size
        if excess > 0:
            del items[:excess]  # the oldest go first
            self.dropped += excess

    def take_until(self, t: float) -> list[Reading]:
        """Remove and return the readings with ``time <= t`` (in time order)."""
        n = bisect.bisect_right(self.items, t, key=lambda r: r.time)
        out, self.items = self.items[:n], self.items[n:]
        return out

    def __len__(self) -> int:
        return len(self.items)


class Aligner:
    """Assigns buffered readings to fusion ticks (see the module docstring)."""

    def __init__(
        self,
        sensors: Sequence[str],
        rate_hz: float,
        start: float,
        alignment: Literal["all", "closest"] = "all",
        lag: float = 0.0,
        buffer_size: int = 256,
    ) -> None:
        if alignment not in ("all", "closest"):
            raise ConfigError(invalid("alignment", alignment, "'all' or 'closest'"))
        if not (rate_hz > 0 and math.isfinite(rate_hz)):
            raise ConfigError(invalid("rate_hz", rate_hz, "a finite number > 0"))
        self.order = {s: i for i, s in enumerate(sensors)}
        self.period = 1.0 / rate_hz
        self.start = float(start)
        self.alignment = alignment
        self.lag = float(lag)
        self.buffers = {s: SensorBuffer(buffer_size) for s in sensors}
        self.last_tick = 0  # tick 0 is the prior
        self.superseded = 0
        self.pending = 0  # buffered readings, all sensors

    def tick_time(self, k: int) -> float:
        return self.start + k * self.period

    def window_end(self, k: int) -> float:
        if k == 0:
            return self.start
        half = 0.5 * self.period if self.alignment == "closest" else 0.0
        return self.tick_time(k) + half

    @property
    def fused_until(self) -> float:
        """Readings at or before this time can no longer be fused."""
        return self.window_end(self.last_tick)

    def is_late(self, t: float) -> bool:
        return t <= self.fused_until

    def push(self, reading: Reading) -> None:
        buf = self.buffers[reading.sensor]
        before = buf.dropped
        buf.push(reading)
        self.pending += 1 - (buf.dropped - before)

    def push_all(self, readings: Sequence[Reading]) -> None:
        """:meth:`push` each of ``readings`` (arrival order), each sensor's buffer at once."""
        by_sensor: dict[str, list[Reading]] = {}
        for r in readings:
            by_sensor.setdefault(r.sensor, []).append(r)
        for sensor, rs in by_sensor.items():
            buf = self.buffers[sensor]
            before = buf.dropped
            buf.extend(rs)
            self.pending += len(rs) - (buf.dropped - before)

    def due(self, clock: float, limit: int = 1_000_000) -> list[int]:
        """The ticks whose window has closed by ``clock`` (their end + lag <= clock), at most
        ``limit`` of them."""
        ticks: list[int] = []
        k = self.last_tick + 1
        while len(ticks) < limit and self.window_end(k) + self.lag <= clock:
            ticks.append(k)
            k += 1
        return ticks

    def take(self, k: int) -> list[Reading]:
        """The readings tick ``k`` fuses (``k`` must be the next tick), in fusion order."""
        if k != self.last_tick + 1:
            raise ConfigError(invalid("tick", k, f"the next tick, {self.last_tick + 1}"))
        end = self.window_end(k)
        self.last_tick = k
        chosen: list[Reading] = []
        for buf in self.buffers.values():
            window = buf.take_until(end)
            if not window:
                continue
            self.pending -= len(window)
            if self.alignment == "all":
                chosen.extend(window)
            else:
                t = self.tick_time(k)
                best = min(window, key=lambda r: (abs(r.time - t), r.time, r.id))
                self.superseded += len(window) - 1
                chosen.append(best)
        return sorted(chosen, key=lambda r: (r.time, self.order[r.sensor], r.id))
