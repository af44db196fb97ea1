"""Node clocks and the time synchronisation of a heterogeneous sensor network (Kushwaha 2010, Ch. III).

The paper's network has two kinds of nodes and synchronises each the way that suits it
(Amundson et al. 2008, cited as [141]): on the multi-hop mote network the routing service
translates event timestamps hop by hop (elapsed time on arrival, RITS-like); on the 802.11b PC
network the video nodes, gateways and fusion node use reference broadcast synchronisation (RBS,
Elson et al. 2002); the mote–PC gateways translate between the two timescales. The dissertation
gives no accuracy figure; the companion paper reports microseconds over several hops.

Everything here works on simulated clocks ``local(t) = (1 + ρ) t + o`` (plus optional jumps) and
returns the *residual* error of each translated timestamp, so experiments can check it is far
below the 250 ms fusion period and can inject larger errors to see what they cost.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, invalid


@dataclass(frozen=True)
class NodeClock:
    """``local(t) = (1 + skew) t + offset`` + the sum of ``jumps`` (true time, size) already passed."""

    offset: float = 0.0
    skew: float = 0.0
    jumps: tuple[tuple[float, float], ...] = ()

    @classmethod
    def random(
        cls, rng: np.random.Generator, max_ppm: float = 50.0, max_offset: float = 1.0
    ) -> NodeClock:
        """Spec 003 §2.4 [C]: ρ ~ U[-50, 50] ppm, o ~ U[0, 1] s."""
        return cls(float(rng.uniform(0, max_offset)), float(rng.uniform(-max_ppm, max_ppm) * 1e-6))

    def local(self, t: ArrayLike) -> NDArray[np.float64]:
        tt = np.asarray(t, float)
        out = (1 + self.skew) * tt + self.offset
        for when, size in self.jumps:
            out = out + np.where(tt >= when, size, 0.0)
        return out

    def true_time(self, local: ArrayLike) -> NDArray[np.float64]:
        """Inverse of :meth:`local` for a clock without jumps."""
        if self.jumps:
            raise ConfigError(invalid("jumps", self.jumps, "no jumps for the inverse"))
        return (np.asarray(local, float) - self.offset) / (1 + self.skew)


def fit_clock_map(x_local: ArrayLike, y_local: ArrayLike) -> tuple[float, float]:
    """Least-squares line ``y ≈ a + b x`` between two clocks' readings of the same events
    (RBS: both receivers timestamp the same reference broadcasts; Elson et al. 2002)."""
    x = np.asarray(x_local, float)
    y = np.asarray(y_local, float)
    if x.size < 2:
        raise ConfigError(invalid("beacons", x.size, "at least 2 common reference broadcasts"))
    xm, ym = x.mean(), y.mean()
    dx = x - xm
    b = float(dx @ (y - ym) / (dx @ dx)) if dx @ dx > 0 else 1.0
    return float(ym - b * xm), b


@dataclass
class RbsDomain:
    """Reference broadcast synchronisation of PC nodes to a reference receiver's timescale.

    A broadcaster sends a beacon every ``period`` s; each receiver timestamps its reception
    with its own clock plus reception jitter (``jitter`` s std: interrupt latency, not the
    sender's delay, which RBS cancels). A node's local time is translated into the reference
    node's time by the line fitted over the last ``window`` beacons before that time
    (spec 003 §2.4 [C]: 8 beacons, one per second)."""

    clocks: dict[str, NodeClock]
    reference: str
    rng: np.random.Generator
    period: float = 1.0
    window: int = 8
    jitter: float = 10e-6
    beacons: NDArray[np.float64] = field(default_factory=lambda: np.empty(0))
    stamps: dict[str, NDArray[np.float64]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.reference not in self.clocks:
            raise ConfigError(invalid("reference", self.reference, f"one of {sorted(self.clocks)}"))

    def broadcast_until(self, t_end: float, t_start: float = -10.0) -> None:
        self.beacons = np.arange(t_start, t_end + self.period, self.period)
        self.stamps = {
            k: c.local(self.beacons) + self.rng.normal(0, self.jitter, self.beacons.size)
            for k, c in self.clocks.items()
        }

    def beacons_for(self, node: str, local: float) -> slice:
        """The beacons :meth:`to_reference` fits for ``local``: the last ``window`` received
        before it (the first ``window`` if fewer than two were)."""
        s = self.stamps[node]
        n = int(np.searchsorted(s, local, side="right"))
        lo = max(0, n - self.window)
        if n - lo < 2:
            lo, n = 0, min(self.window, s.size)
        return slice(lo, n)

    def to_reference(self, node: str, local: float) -> float:
        """``local`` (node clock) → reference clock, from the beacons received before it."""
        used = self.beacons_for(node, local)
        a, b = fit_clock_map(self.stamps[node][used], self.stamps[self.reference][used])
        return a + b * local


@dataclass(frozen=True)
class HopTranslation:
    """Elapsed-time-on-arrival translation along a multi-hop mote route (RITS-like).

    The message carries the time elapsed since the event; each node adds its residence time
    measured with its own clock; the receiver subtracts the accumulated elapsed time from its
    reception time. The error is Σ skew_i × residence_i plus per-hop timestamping jitter
    (spec 003 §2.4 [C]: N(0, (5 µs)²))."""

    jitter: float = 5e-6

    def translate(
        self,
        event_true: float,
        route: Sequence[NodeClock],
        residence: Sequence[float],
        link_delay: Sequence[float],
        rng: np.random.Generator,
    ) -> tuple[float, float]:
        """Event time in the last node's clock, and the true time of arrival there.

        ``route[0]`` is the source node; ``residence[i]`` how long the message stays at
        ``route[i]``; ``link_delay[i]`` the air time from ``route[i]`` to ``route[i + 1]``
        (known to the receiver up to the jitter, as in RITS)."""
        if not (len(residence) == len(link_delay) == len(route) - 1):
            raise ConfigError(
                invalid("route", len(route), "len(residence) + 1 == len(link_delay) + 1 nodes")
            )
        t = event_true
        elapsed = 0.0
        for clock, stay, delay in zip(route[:-1], residence, link_delay):
            elapsed += float(clock.local(t + stay) - clock.local(t)) + rng.normal(0, self.jitter)
            t += stay + delay
            elapsed += delay  # compensated air time
        return float(route[-1].local(t)) - elapsed + rng.normal(0, self.jitter), t
