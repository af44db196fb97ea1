"""The fusion node's input side: per-sensor ring buffers and the closest-in-time scheduler.

Kushwaha 2010, Ch. III: detections arrive time-stamped in one timescale and are stored in one
circular buffer per sensor; a periodic scheduler (4 Hz) issues a fusion timestamp t and takes,
from each sensor, the buffered measurement whose timestamp is closest to t. This decouples the
tracking rate from the sensing rates.

Bad input never stops the node; it is counted in :class:`IntakeStats` and skipped: unknown
sensors, detection functions of the wrong length or with non-finite values, duplicated packets
(same sequence number), packets that arrive too late to matter, and clock jumps (a timestamp
that disagrees with the sensor's sequence numbers by more than ``jump_tolerance``; the sensor is
then trusted again once its timestamps are consistent).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class Packet:
    """One detection as it reaches the fusion node (timestamp already translated)."""

    sensor_id: str
    seq: int
    timestamp: float
    values: NDArray[np.float64]
    arrival: float = 0.0


@dataclass
class IntakeStats:
    received: int = 0
    accepted: int = 0
    unknown_sensor: int = 0
    wrong_length: int = 0
    non_finite: int = 0
    duplicate: int = 0
    late: int = 0
    clock_jump: int = 0
    missing_at_tick: int = 0

    def as_dict(self) -> dict[str, int]:
        return dict(self.__dict__)


@dataclass
class FusionScheduler:
    """Ring buffers (``capacity`` packets per sensor) and the closest-timestamp selection.

    ``lengths`` maps each known sensor to the length of its detection function; ``period`` is the
    sensor's nominal reporting period (for the clock-jump check); ``max_offset`` is how far from
    the fusion timestamp a measurement may be and still be used (default: half a fusion period)."""

    lengths: Mapping[str, int]
    period: float = 0.25
    capacity: int = 16
    max_offset: float = 0.125
    late_after: float = 2.0
    jump_tolerance: float = 0.5
    stats: IntakeStats = field(default_factory=IntakeStats)
    _buffers: dict[str, deque[Packet]] = field(default_factory=dict)
    _last_tick: float = -np.inf

    def receive(self, packet: Packet) -> bool:
        """Store a packet; returns False (and counts why) when it is rejected."""
        s = self.stats
        s.received += 1
        if packet.sensor_id not in self.lengths:
            s.unknown_sensor += 1
            return False
        v = np.asarray(packet.values, float)
        if v.shape != (self.lengths[packet.sensor_id],):
            s.wrong_length += 1
            return False
        if not np.all(np.isfinite(v)):
            s.non_finite += 1
            return False
        if packet.timestamp < self._last_tick - self.late_after:
            s.late += 1
            return False
        buf = self._buffers.setdefault(packet.sensor_id, deque(maxlen=self.capacity))
        if any(p.seq == packet.seq for p in buf):
            s.duplicate += 1
            return False
        ref = max(buf, key=lambda p: p.seq, default=None)
        if ref is not None:
            expected = ref.timestamp + (packet.seq - ref.seq) * self.period
            if (
                abs(packet.timestamp - expected)
                > self.jump_tolerance + 0.05 * abs(packet.seq - ref.seq) * self.period
            ):
                s.clock_jump += 1
                buf.clear()  # start afresh from this packet: the old timescale is gone
        buf.append(packet)
        s.accepted += 1
        return True

    def take(self, t: float) -> dict[str, Packet]:
        """For fusion timestamp ``t``: each sensor's buffered packet closest in time (within ``max_offset``)."""
        self._last_tick = max(self._last_tick, t)
        out = {}
        for sid in self.lengths:
            buf = self._buffers.get(sid)
            if not buf:
                self.stats.missing_at_tick += 1
                continue
            best = min(buf, key=lambda p: abs(p.timestamp - t))
            if abs(best.timestamp - t) <= self.max_offset:
                out[sid] = best
            else:
                self.stats.missing_at_tick += 1
        return out
