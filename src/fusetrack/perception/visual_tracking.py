"""Running a fusetrack particle filter over video frames, and scoring the track.

The filters are the ordinary ones (:class:`~fusetrack.filters.sis.ProposalParticleFilter` with any
proposal, :class:`~fusetrack.filters.multiple_model.MultipleModelParticleFilter`); a frame
becomes their measurements through a ``measure`` callable, so the same loop serves the
edge-contour trackers (Zhai 2007, Secs. 3.6 and 4.3: the measurement is the frame's edge map) and
the multi-cue tracker (Sec. 5.4: the measurements are cue locations found in an aid window around
the predicted centre, with templates that adapt to the estimate).

Track loss (spec 001, claim C17): the centre error exceeds the target's half-size for at least
``frames`` consecutive frames.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from ..core.beliefs import Gaussian
from ..core.measurement import Measurement

Array = NDArray[np.float64]


class FrameFilter(Protocol):
    def initialize(self, prior: Gaussian, rng: np.random.Generator) -> Any: ...

    def step(
        self, state: Any, dt: float, measurements: Sequence[Measurement], rng: np.random.Generator
    ) -> Any: ...


class FrontEnd(Protocol):
    """Turns a frame into one measurement per sensor of the filter."""

    def measure(self, frame: NDArray[np.uint8], predicted: Array) -> list[Array | None]: ...

    def adapt(self, frame: NDArray[np.uint8], estimate: Array) -> None: ...


@dataclass
class Track:
    """Estimates ``(T, d)`` (row 0 = the prior mean at frame 0) and the seconds it took."""

    estimates: Array
    seconds: float
    info: dict[str, Any]


def predicted_centre(estimate: Array) -> Array:
    """Where the aid window goes: the estimate moved one frame at its velocity."""
    return np.asarray(estimate[:2] + estimate[2:4], dtype=np.float64)


def track_frames(
    filt: FrameFilter,
    prior: Gaussian,
    frames: Sequence[NDArray[np.uint8]] | NDArray[np.uint8],
    front_end: FrontEnd,
    rng: np.random.Generator,
    *,
    after_step: Callable[[Any, int], Any] | None = None,
) -> Track:
    """Filter frames 1..T-1 (frame 0 is where the prior was set); ``after_step(state, k)`` may
    return a modified state (e.g. App. B's shared velocity)."""
    t0 = time.perf_counter()
    state = filt.initialize(prior, rng)
    est = [np.asarray(prior.mean, float)]
    front_end.adapt(frames[0], est[0])
    for k in range(1, len(frames)):
        zs = front_end.measure(frames[k], predicted_centre(est[-1]))
        ids = getattr(filt, "sensor_ids", None) or [s.sensor_id for s in filt.sensors]  # type: ignore[attr-defined]
        ms = [
            Measurement(float(k), i, np.asarray(z, float)) for i, z in zip(ids, zs) if z is not None
        ]
        state = filt.step(state, 1.0, ms, rng)
        if after_step is not None:
            state = after_step(state, k)
        e = np.asarray(state.estimate, float)
        est.append(e)
        front_end.adapt(frames[k], e)
    stats = getattr(filt, "stats", None)
    info: dict[str, Any] = dict(stats.as_dict()) if stats is not None else {}
    return Track(np.array(est), time.perf_counter() - t0, info)


@dataclass(frozen=True)
class GaussianFrameState:
    """A Gaussian filter's belief (or an IMM's) and its point estimate."""

    belief: Any
    estimate: Array


@dataclass
class GaussianFrameFilter:
    """A fusetrack Gaussian filter (EKF, UKF, or an IMM over them) as a frame filter: per frame
    ``predict``, then ``update`` with the front end's measurements that are not ``None``. The
    sensors' ``predict``/``residual`` must give a measurement function of the state (e.g. the
    ellipse-edge sensor's centre pseudo-measurement, or a cue location)."""

    filt: Any
    sensor_ids: Sequence[str]

    def initialize(self, prior: Gaussian, rng: np.random.Generator) -> GaussianFrameState:
        belief = self.filt.initialize(prior) if hasattr(self.filt, "initialize") else prior
        return GaussianFrameState(belief, np.asarray(belief.mean, float))

    def step(
        self,
        state: GaussianFrameState,
        dt: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator,
    ) -> GaussianFrameState:
        belief = self.filt.predict(state.belief, dt)
        ms = [m for m in measurements if m.is_finite]
        if ms:
            belief = self.filt.update(belief, ms)
        return GaussianFrameState(belief, np.asarray(belief.mean, float))

    @property
    def stats(self) -> Any:
        return getattr(self.filt, "stats", None)


@dataclass
class PrecomputedMeasurements:
    """A front end for measurements that do not depend on the tracker (e.g. edge maps)."""

    zs: Sequence[list[Array | None]]
    _k: int = 0

    def measure(self, frame: NDArray[np.uint8], predicted: Array) -> list[Array | None]:
        self._k += 1
        return self.zs[self._k]

    def adapt(self, frame: NDArray[np.uint8], estimate: Array) -> None:
        return None


def lost_frames(error: Array, half_size: Array | float, frames: int = 5) -> tuple[bool, int]:
    """``(lost, first frame of the first run of >= frames errors above half_size)`` (-1 if kept)."""
    bad = np.asarray(error) > np.asarray(half_size)
    run = 0
    for k, b in enumerate(bad):
        run = run + 1 if b else 0
        if run >= frames:
            return True, k - frames + 1
    return False, -1
