"""What no tracker can beat on Kushwaha 2010's simulated road (issue 19, item 3): the PCRB of a
vehicle's position from the bearings the road's arrays and cameras measure, along each run's
own truth, beside the Ch. III error tables.

**Measurements.** The trackers fuse detection functions (36 beam energies per acoustic node, 160
column counts per camera), not bearings; the paper gives no DOA accuracy (spec 003 E1). The
bound takes the bearings those functions point at, with the noise our simulated sensors show:

* a node's DOA is its strongest beam (heading + beam angle, as :mod:`.beamformer`'s trials), its
  error taken against the bearing of the engine (the acoustic source, 1.5 m ahead of the centre
  of mass, a known offset along the known direction of travel: it moves the bound's state by a
  known amount and leaves the bound unchanged);
* a camera's bearing is the mean of the Gaussian-mixture component (:func:`fit_angle_mixture`,
  as the trackers fit it) nearest the vehicle's centre of mass, only while the centre is in its
  field of view (known association: with several vehicles each is given its own component);
* per modality one noise ``sigma``: the robust spread ``1.4826 MAD`` of all the runs' bearing
  errors about each sensor's median over its pass (:func:`robust_sigma`; with several vehicles,
  the bearings of a vehicle alone in a camera's view, elsewhere a component is often a merged
  blob's). A bias that stays over a pass (the 10 cm array's anisotropy at engine frequencies,
  the smoothing lag, a silhouette's offset) and gross errors (a wrong peak) are left out: both
  only lower the information, so the bound is that of the sensors' Gaussian core, below what
  their biases and outliers allow.

A bearing with noise ``sigma`` at horizontal range ``r`` adds ``u u^T / (sigma^2 r^2)`` to the
position information (``u`` the unit vector across the line of sight;
:class:`~fusetrack.sensors.Bearing`).

**Motion and prior.** The trackers' motion model: nearly constant velocity with white
acceleration of 2 m/s² per 0.25 s step (MCMCDA's ``accel_std``; rank-2 noise, so the covariance
form of :func:`~fusetrack.evaluation.posterior_crlb`),
along the run's true constant-velocity path; the grid SBE's directional model has no Gaussian
form. Prior ``N(truth, PRIOR_COV)`` before the first tick: 10 m in position (half the field),
15 m/s in velocity (either direction at up to 13.4 m/s) -- what a tracker knows before it has
heard anything.

**Comparisons.** Only ticks with two or more bearings count (:class:`PassBound`). The bound
bounds the mean square error: a tracker's RMS position error over those of its ticks is compared
with ``sqrt(mean_k trace B_k)`` over the same ticks (a tracker below it by more than 3 standard
errors means a wrong tracker or a wrong bound). The paper's numbers
are mean Euclidean errors; assuming centred Gaussian errors with covariance at least ``B_k``,
their bound is ``mean_k E|N(0, B_k)|`` (:func:`~fusetrack.evaluation.expected_norm`), and a
paper number below it is *impossible on the printed model* (under that assumption and this
bearing noise).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...association import MCMCDAConfig
from ...evaluation import (
    MARGIN_SE,
    Claim,
    ClaimKinds,
    expected_norm,
    possible_claim,
    posterior_crlb,
    rms_over_runs,
)
from ...management import Packet
from ...motion import ConstantVelocity
from ...perception import fit_angle_mixture
from ...sensors import AngularSampling, Bearing
from .scene import CAMERA_FOV, DT, VARIANTS, VIDEO_ANGLES, FusionInput, Layout, SinglePass

Array = NDArray[np.float64]
PRIOR_COV = np.diag([10.0**2, 10.0**2, 15.0**2, 15.0**2])
"""The bound's prior covariance of ``[x, y, vx, vy]`` about the truth before the first tick."""
BEAM_ANGLES = AngularSampling.beams(36).angles
MODALITY_SETS = {"A": ("audio",), "V": ("video",), "AV": ("audio", "video")}


def modality_set(variant: str) -> str:
    """The :data:`MODALITY_SETS` name of an SBE approach's sensors (:data:`.scene.VARIANTS`)."""
    sensors = VARIANTS[variant][0]
    return next(k for k, v in MODALITY_SETS.items() if v == sensors)


def tracker_motion() -> ConstantVelocity:
    """Nearly constant velocity, white acceleration of MCMCDA's ``accel_std`` (2 m/s²) per step."""
    return ConstantVelocity(ndim=2, q=MCMCDAConfig().accel_std ** 2, noise="discrete")


def _wrap(a: Array) -> Array:
    return np.asarray(np.mod(np.asarray(a, float) + np.pi, 2 * np.pi) - np.pi)


def true_bearings(sensors: Sequence[tuple[str, float, float, float]], points: Array) -> Array:
    """World bearings ``(..., S)`` from each sensor ``(id, x, y, heading)`` to ``points``
    ``(..., 2)``."""
    xy = np.array([[s[1], s[2]] for s in sensors])
    d = np.asarray(points, float)[..., None, :] - xy
    return np.asarray(np.arctan2(d[..., 1], d[..., 0]))


def audio_doa_errors(layout: Layout, taken: Sequence[Mapping[str, Packet]], source: Array) -> Array:
    """``(T, 6)``: each node's strongest-beam DOA minus the true bearing of ``source`` ``(T, 2)``
    at each tick (NaN where the fusion node took no packet of that node)."""
    truth = true_bearings(layout.audio, source)
    out = np.full(truth.shape, np.nan)
    for k, packets in enumerate(taken):
        for s, (sid, _, _, heading) in enumerate(layout.audio):
            p = packets.get(sid)
            if p is not None:
                est = heading + BEAM_ANGLES[int(np.argmax(p.values))]
                out[k, s] = _wrap(est - truth[k, s])
    return out


def video_bearing_errors(
    layout: Layout, taken: Sequence[Mapping[str, Packet]], centres: Array, apart: float = 0.0
) -> Array:
    """``(T, 3, n)``: per camera, the mixture component nearest each of the ``n`` vehicles'
    centres ``(T, n, 2)`` minus its true bearing (NaN where the camera took no packet, fitted no
    component, the centre is outside its field of view, or within ``apart`` rad of another
    vehicle's: the camera sees one blob for both)."""
    c = np.asarray(centres, float).reshape(len(taken), -1, 2)
    truth = true_bearings(layout.video, c).transpose(0, 2, 1)  # (T, S, n)
    yaws = np.array([v[3] for v in layout.video])[None, :, None]
    in_view = np.abs(_wrap(truth - yaws)) <= CAMERA_FOV / 2  # (T, S, n)
    gap = np.abs(_wrap(truth[..., :, None] - truth[..., None, :]))
    gap = np.where(in_view[..., None, :], gap, np.inf)  # only vehicles in view merge
    gap[..., np.arange(c.shape[1]), np.arange(c.shape[1])] = np.inf
    alone = gap.min(axis=-1) >= apart  # (T, S, n)
    out = np.full(truth.shape, np.nan)
    for k, packets in enumerate(taken):
        for s, (sid, _, _, yaw) in enumerate(layout.video):
            p = packets.get(sid)
            if p is None:
                continue
            mix = fit_angle_mixture(p.values, VIDEO_ANGLES, min_mass=20.0)
            if mix.empty:
                continue
            seen = in_view[k, s] & alone[k, s]
            diff = _wrap(yaw + mix.means[:, None] - truth[k, s][None, :])  # (components, n)
            nearest = diff[np.argmin(np.abs(diff), axis=0), np.arange(diff.shape[1])]
            out[k, s] = np.where(seen, nearest, np.nan)
    return out


def bearing_record(layout: Layout, sim: SinglePass, fin: FusionInput) -> dict[str, Any]:
    """What the PCRB needs of one single-vehicle pass (:func:`pass_bounds`): the bearing errors
    of every node and camera at every tick, the true path of the centre and the engine, the
    velocity."""
    engine = sim.vehicle.engine(sim.rec.ticks)[:, :2]
    return {
        "audio": audio_doa_errors(layout, fin.taken, engine).tolist(),
        "video": video_bearing_errors(layout, fin.taken, sim.truth[:, None])[..., 0].tolist(),
        "centre": sim.truth.tolist(),
        "engine": engine.tolist(),
        "velocity": [sim.vehicle.speed, 0.0],
    }


def robust_sigma(errors: Sequence[Array]) -> float:
    """The spread of the bearing errors' Gaussian core (rad): ``1.4826 MAD`` of every finite
    error of the passes ``errors`` (each ``(T, S, ...)``) about its sensor's median over its pass.

    A bias that stays over a pass (the array's anisotropy at engine frequencies, the smoothing
    lag, the silhouette's offset) is left out: unknown to the trackers, it only lowers the
    information, so a bound without it stays below."""
    parts = []
    for e in errors:
        a = np.asarray(e, float)
        if np.isfinite(a).any():
            with warnings.catch_warnings():  # a sensor without any bearing: its median is NaN
                warnings.simplefilter("ignore", RuntimeWarning)
                parts.append((a - np.nanmedian(a, axis=0)).ravel())
    e = np.concatenate(parts) if parts else np.empty(0)
    e = e[np.isfinite(e)]
    if e.size < 2:
        return float("nan")
    return float(1.4826 * np.median(np.abs(e - np.median(e))))


@dataclass(frozen=True)
class BearingNoise:
    """One bearing noise per modality (rad)."""

    audio: float
    video: float

    def of(self, modality: str) -> float:
        return self.audio if modality == "audio" else self.video


def position_bound(
    layout: Layout,
    noise: BearingNoise,
    points: Mapping[str, Array],
    velocity: Array,
    reported: Mapping[str, Array],
) -> Array:
    """The PCRB's position block ``(T, 2, 2)`` (m²) of one vehicle along its true path.

    ``points``: per modality (``"audio"``, ``"video"``) the point its sensors see ``(T, 2)``
    (the engine, the centre of mass; the state is the centre of mass, a known offset away);
    ``velocity``: the true velocity ``(2,)`` or ``(T, 2)``; ``reported``: per modality in the
    bound, ``(T, S)`` booleans, which sensor gave the vehicle a bearing at which tick. Modalities
    absent from ``reported`` add nothing."""
    sensors, info, masks = [], [], []
    for modality, mask in reported.items():
        nodes = layout.audio if modality == "audio" else layout.video
        p = np.asarray(points[modality], float)
        states = np.column_stack([p, np.broadcast_to(velocity, p.shape)])
        for s, (sid, x, y, _) in enumerate(nodes):
            b = Bearing(sid, (x, y), sigma=noise.of(modality), position_index=(0, 1))
            sensors.append(b)
            info.append(b.fisher_information(states))
            masks.append(np.asarray(mask, bool)[:, s])
    centre = np.asarray(points.get("video", points.get("audio")), float)
    truth = np.column_stack([centre, np.broadcast_to(velocity, centre.shape)])
    B = posterior_crlb(
        tracker_motion(),
        sensors,
        truth,
        DT,
        PRIOR_COV,
        mask=np.column_stack(masks),
        information=np.stack(info, axis=1),
    )
    return np.asarray(B[:, :2, :2])


def noise_of(records: Sequence[Mapping[str, Packet]]) -> BearingNoise:
    """:class:`BearingNoise` pooled over the runs' bearing records (``"audio"``: ``(T, 6)``,
    ``"video"``: ``(T, 3, ...)`` errors in rad; ``"video_clean"``, where given, in place of
    ``"video"``: the bearings of a vehicle alone in a camera's view, unless there are none; a
    modality missing from every record is NaN)."""

    def pooled(keys: tuple[str, ...]) -> float:
        for key in keys:  # the first key whose errors give a spread
            sigma = robust_sigma([np.asarray(r[key], float) for r in records if key in r])
            if np.isfinite(sigma):
                return sigma
        return float("nan")

    return BearingNoise(pooled(("audio",)), pooled(("video_clean", "video")))


def pass_bounds(
    layout: Layout, noise: BearingNoise, record: Mapping[str, object], vehicle: int | None = None
) -> dict[str, PassBound]:
    """:class:`PassBound` of one pass per modality set of :data:`MODALITY_SETS`
    whose modalities the record holds. ``record``: ``"audio"`` ``(T, 6)`` and/or ``"video"``
    ``(T, 3)`` bearing errors (NaN: no bearing), ``"centre"`` ``(T, 2)``, ``"engine"``
    ``(T, 2)``, ``"velocity"`` ``(2,)``; with ``vehicle``, ``"video"`` ``(T, 3, n)``,
    ``"centre"`` ``(T, n, 2)`` and ``"velocity"`` ``(n, 2)`` are taken at that vehicle."""

    def at(key: str) -> Array:
        a = np.asarray(record[key], float)
        if vehicle is None:
            return a
        if key == "video":
            return a[..., vehicle]
        return a[:, vehicle] if key == "centre" else a[vehicle]

    centre = at("centre")
    points = {"video": centre, "audio": np.asarray(record.get("engine", centre), float)}
    out = {}
    for name, modalities in MODALITY_SETS.items():
        if all(m in record for m in modalities):
            reported = {m: np.isfinite(at(m)) for m in modalities}
            B = position_bound(layout, noise, points, at("velocity"), reported)
            crossed = sum(r.reshape(len(B), -1).sum(axis=1) for r in reported.values()) >= 2
            out[name] = PassBound(B, np.asarray(crossed, bool))
    return out


@dataclass(frozen=True)
class PassBound:
    """The position bound ``B`` ``(T, 2, 2)`` of one vehicle's pass and which ticks are
    ``crossed`` ``(T,)``: two or more bearings. At a tick with one bearing the position along
    its ray is known only from the prior and the field's edges, which the trackers' grid knows
    and a Gaussian prior cannot express; the comparisons keep the crossed ticks."""

    B: Array
    crossed: Array

    def over(self, ticks: Sequence[int], errors: Sequence[float]) -> tuple[float, float, float]:
        """``(RMS error, mean-error bound, RMS bound)`` over the crossed ones of ``ticks``
        (``errors``: the tracker's error at each of ``ticks``): ``sqrt(mean e_k^2)``,
        ``mean_k E|N(0, B_k)|`` and ``sqrt(mean_k trace B_k)`` (NaN for none)."""
        idx = np.asarray(ticks, int)
        keep = self.crossed[idx] if idx.size else np.zeros(0, bool)
        if not keep.any():
            return float("nan"), float("nan"), float("nan")
        b = self.B[idx[keep]]
        e = np.asarray(errors, float)[keep]
        return (
            float(np.sqrt(np.mean(e**2))),
            float(expected_norm(b).mean()),
            float(np.sqrt(np.trace(b, axis1=-2, axis2=-1).mean())),
        )


@dataclass(frozen=True)
class BoundRow:
    """One group of tracks (an approach, a vehicle): its tracks' RMS errors ``rms`` (one per
    track), and the bound over each track's own ticks, ``bound_mean`` and ``bound_rms``."""

    rms: Array
    bound_mean: Array
    bound_rms: Array

    @property
    def ours(self) -> tuple[float, float]:
        """RMS over tracks of the per-track RMS error, and its standard error."""
        return rms_over_runs(self.rms)

    @property
    def bound(self) -> tuple[float, float]:
        """``(mean-error bound, RMS bound)`` over the tracks' ticks (tracks weighted equally)."""
        return float(np.mean(self.bound_mean)), float(np.sqrt(np.mean(self.bound_rms**2)))

    def above(self) -> bool:
        """Our RMS is not more than :data:`MARGIN_SE` standard errors below the RMS bound."""
        value, se = self.ours
        return bool(value >= self.bound[1] - MARGIN_SE * (se if np.isfinite(se) else 0.0))


def bound_row(
    rms: Sequence[float], bound_mean: Sequence[float], bound_rms: Sequence[float]
) -> BoundRow:
    """:class:`BoundRow` of the tracks with a finite error (the others are dropped)."""
    r, m, b = (np.asarray(v, float) for v in (rms, bound_mean, bound_rms))
    ok = np.isfinite(r) & np.isfinite(m) & np.isfinite(b)
    return BoundRow(r[ok], m[ok], b[ok])


def above_bound_claim(
    kinds: ClaimKinds, claim_id: str, what: str, rows: Mapping[str, BoundRow]
) -> Claim:
    """Diagnostic: every group's RMS position error is not below the PCRB's RMS over the same
    ticks (by more than :data:`MARGIN_SE` s.e.). Fails only if a tracker or the bound is wrong."""
    rows = {k: r for k, r in rows.items() if r.rms.size}
    ratios = {k: round(r.ours[0] / r.bound[1], 3) for k, r in rows.items()}
    return kinds.claim(
        claim_id,
        f"{what}: RMS position error not below the PCRB of the bearings (same ticks); "
        "ours: RMS / bound per group",
        "not in the paper",
        ratios,
        f"RMS >= bound - {MARGIN_SE:g} s.e. in every group",
        bool(rows) and all(r.above() for r in rows.values()),
    )


def paper_possible_claims(
    kinds: ClaimKinds,
    prefix: str,
    what: str,
    paper: Mapping[str, float],
    bound: Mapping[str, float],
) -> list[Claim]:
    """Diagnostic per printed mean error: not below the mean-error bound (Gaussian errors) of
    the bearings; a failure labels it *impossible on the printed model*."""
    return [
        possible_claim(
            kinds,
            f"{prefix}_{key}_possible",
            f"{what} {key} ({value:g} m) against the PCRB's mean-error bound",
            value,
            (float("nan"), float("nan")),
            bound=bound[key],
        )
        for key, value in paper.items()
        if key in bound and np.isfinite(bound[key])
    ]


__all__ = [
    "MODALITY_SETS",
    "PRIOR_COV",
    "BearingNoise",
    "BoundRow",
    "PassBound",
    "above_bound_claim",
    "audio_doa_errors",
    "bearing_record",
    "bound_row",
    "modality_set",
    "noise_of",
    "paper_possible_claims",
    "pass_bounds",
    "position_bound",
    "robust_sigma",
    "tracker_motion",
    "true_bearings",
    "video_bearing_errors",
]
