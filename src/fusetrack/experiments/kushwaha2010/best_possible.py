"""What no tracker can beat on Kushwaha 2010's Ch. V smart-camera runs (issue 19, item 3): the
posterior Cramér-Rao bound (PCRB) of the 3-D position beside every camera report's error table,
a trivial estimator, and the claim that every tracker's error lies above the bound.

**The measurement model the bound is for.** An idealised detector: at every step each camera
that sees the target reports the pixel of its centre, ``z_n = pi(P_n [x; 1]) + v_n``,
``v_n ~ N(0, sigma^2 I_2)``, the point projection of the camera matrix ``P_n`` of the run
(:attr:`~fusetrack.sensors.EllipsoidCamera.P`). ``sigma`` = :data:`PIXEL_SIGMA` =
``1 / sqrt(12)`` px ~ 0.29 px is our choice ([C]): the dissertation and spec 003 give no
measurement noise for Ch. V (the only pixel spread in the spec, ``Sigma_pix = (8 px)^2``, is
tracker T3's image-plane proposal, and ours is 6 px). It is the spread of rounding the centre to
its pixel (uniform over the pixel, variance 1/12 px^2 per axis), so the bound is that of a
*pixel-exact* detector with no other error, taken Gaussian with the same variance (uniform noise
has no finite Fisher information). One pixel (the Nott 2009 bound's camera) is not a floor here:
the trackers' mean 2-D reprojection error is itself about 1 px in setup B, and at 1 px the closed
form T4-eq103 came out below the bound in a quick run of setup B. The trackers do not see a point:
they score appearance histograms over projected ellipses (Eqs. 70-76), and a blob of many pixels
can in principle be located below a pixel, so the bound compares them with this idealised
detector, not with the images' full information. With the process noise below the bound is
nearly proportional to ``sigma`` where the cameras dominate (up to 3.4 times higher at 1 px).

A camera carries information at a step when it sees the target: its rendered frame shows at least
12 target pixels (``Frames.participating``, which is False where the target has left the view or
is hidden, the one-camera gap) and, in the occlusion runs, at least 12 of them are not covered by
the occluder. Unseen steps carry none (the PCRB's mask).

**Motion and prior.** The trackers' own model: the constant-velocity velocity filter of
:class:`~fusetrack.filters.SmartCameraTracker`, state ``[x, y, z, vx, vy, vz]``, one step per
frame (``dt = 1``), white-noise acceleration of PSD ``kf_q`` (``TrackerSettings.kf_q`` = 0.01
m^2/step^3, full-rank ``Q``, the PCRB's information form; Tichavský, Muravchik & Nehorai 1998),
and the manual initialisation's prior ``N(truth at step 0, 0.05^2 I_6)`` (:data:`PRIOR_SD`),
with no measurement at step 0 (the trackers update from step 1). The bound is evaluated along
each run's own simulated truth (one trajectory, ``R = 1``: the run's own bound). The truths are
smooth random paths, not draws from the constant-velocity model, so the bound is the error floor
of the model the trackers assume at the run's geometry and visibility, not a theorem about the
rendered runs; a tracker below it would be a finding to explain (it would have to use knowledge
of the path that the model lacks, or be lucky in a single run).

**Comparisons.** The PCRB bounds the mean square error: trackers are compared by their RMS 3-D
error (root of the mean over runs of each run's mean square error, with its standard error,
:func:`~fusetrack.evaluation.rms_over_runs`) against ``sqrt(mean over runs and steps of trace
B_k[pos])``. The reports' tables give mean Euclidean errors, which may lie below an RMS bound;
assuming each step's error is centred Gaussian with covariance at least ``B_k`` (exact for a
Kalman filter on a linear-Gaussian model), ``E|e_k| >= E|N(0, B_k[pos])|`` (:func:`expected_norm`),
whose mean over the same steps is the *mean-error bound* beside the mean errors.

**Trivial estimator.** The manual initialisation extrapolated at constant velocity,
``x_0 + t v_0`` (truth at step 0, no camera): a tracker worse than it gains nothing from the
cameras.

Kushwaha 2010 prints no number for Ch. V (Figs 47-56 are plots without values; LCR and FGH have
no ground truth), so no paper number is judged against the bound here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from ...core import ShapeError, check_positive, invalid
from ...evaluation import (
    MARGIN_SE,
    Claim,
    ClaimKinds,
    expected_norm,
    posterior_information,
    rms_over_runs,
)
from ...filters import TrackerSettings
from ...motion import ConstantVelocity
from ...sensors import EllipsoidCamera

Array = NDArray[np.float64]

PIXEL_SIGMA = 1.0 / np.sqrt(12.0)
"""The idealised detector's pixel noise (px, [C]: the spec gives none for Ch. V): the spread of
rounding to the pixel, a pixel-exact detector."""
PRIOR_SD = 0.05
"""The manual initialisation's sd of every position and velocity component (m, m/step), as
:meth:`~fusetrack.filters.SmartCameraTracker.initial_belief`."""
STATE_DIM = 6
DEFAULT_SETTINGS = TrackerSettings()
"""The trackers' constants (the experiments use the defaults of the velocity filter)."""
MIN_PIXELS = 12
"""Target pixels a frame must show for its camera to inform (``render_frames``' ``min_pixels``,
the rule of ``Frames.participating``)."""
BOUND_COLUMNS = ("pcrb_mse", "pcrb_mean", "trivial_err")
"""Per-step columns :func:`with_bound` adds to a run's rows: the trace of the bound's position
block (m^2), its Gaussian mean-error bound (m) and the trivial estimator's 3-D error (m)."""
LABELS = {
    "pcrb": "PCRB (best possible)",
    "trivial": "trivial: initial state extrapolated",
}

# --------------------------------------------------------------------------------------------
# the measurement model


@dataclass(frozen=True)
class PointProjection:
    """A camera reporting the pixel ``pi(P [x; 1])`` of the target's centre with noise
    ``N(0, sigma^2 I_2)``, on the 6-D state ``[position, velocity]`` (a
    :class:`~fusetrack.core.SensorModel`). ``P`` ``(3, 4)``: the camera matrix."""

    sensor_id: str
    P: Array
    sigma: float = PIXEL_SIGMA
    dim: int = field(default=2, init=False)
    angular: tuple[bool, ...] = field(default=(False, False), init=False)

    def __post_init__(self) -> None:
        P = np.asarray(self.P, dtype=float)
        if P.shape != (3, 4) or not np.all(np.isfinite(P)):
            raise ShapeError(invalid(f"{self.sensor_id}.P", P.shape, "a finite (3, 4) matrix"))
        check_positive("sigma", self.sigma)
        object.__setattr__(self, "P", P)

    def _homogeneous(self, x: ArrayLike) -> Array:
        p = np.asarray(x, dtype=float)[..., :3]
        return np.asarray(p @ self.P[:, :3].T + self.P[:, 3])

    def predict(self, x: Array) -> Array:
        h = self._homogeneous(x)
        return np.asarray(h[..., :2] / h[..., 2:3])

    def residual(self, z: Array, z_pred: Array) -> Array:
        return np.asarray(np.asarray(z, float) - z_pred)

    def jacobian(self, x: Array) -> Array:
        """``d pi / dx`` ``(..., 2, 6)``: rows ``(P_i[:3] - u_i P_3[:3]) / (P_3 . [x; 1])``."""
        h = self._homogeneous(x)
        uv = h[..., :2] / h[..., 2:3]
        dpos = (self.P[:2, :3] - uv[..., :, None] * self.P[2, :3]) / h[..., 2, None, None]
        return np.concatenate([dpos, np.zeros_like(dpos)], axis=-1)

    def noise_cov(self, x: Array | None = None) -> Array:
        return self.sigma**2 * np.eye(2)

    def log_likelihood(self, z: Array, x: Array) -> Array:
        r = self.residual(z, self.predict(x))
        return np.asarray(
            -0.5 * np.sum(r * r, -1) / self.sigma**2 - np.log(2 * np.pi * self.sigma**2)
        )

    def simulate(self, x: Array, rng: np.random.Generator) -> Array:
        z = self.predict(x)
        return np.asarray(z + self.sigma * rng.standard_normal(z.shape))

    def fisher_information(self, x: Array) -> Array:
        """``H^T H / sigma^2`` ``(..., 6, 6)``."""
        H = self.jacobian(x)
        return np.asarray(np.swapaxes(H, -1, -2) @ H / self.sigma**2)

    def detection_probability(self, x: Array) -> Array:
        """1 where the point is in front of the camera (the visibility mask decides the rest)."""
        return np.asarray(self._homogeneous(x)[..., 2] > 0, dtype=float)


def projections(
    cams: Sequence[EllipsoidCamera], sigma: float = PIXEL_SIGMA
) -> list[PointProjection]:
    """The run's cameras as point-projection sensors."""
    return [PointProjection(c.sensor_id, np.asarray(c.P, float), sigma) for c in cams]


def trackers_motion(settings: TrackerSettings = DEFAULT_SETTINGS) -> ConstantVelocity:
    """The trackers' velocity-filter motion (``SmartCameraTracker.kf``)."""
    return ConstantVelocity(ndim=3, q=settings.kf_q)


# --------------------------------------------------------------------------------------------
# the bound along one run


def _checked(positions: ArrayLike, visible: ArrayLike, n_cams: int) -> tuple[Array, Array]:
    x = np.asarray(positions, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3 or len(x) < 2:
        raise ShapeError(invalid("positions.shape", x.shape, "(T, 3) with T >= 2"))
    seen = np.asarray(visible, dtype=bool)
    if seen.shape != (len(x), n_cams):
        raise ShapeError(invalid("visible.shape", seen.shape, f"(T, cameras) = {(len(x), n_cams)}"))
    return x, seen


def position_bound(
    cams: Sequence[EllipsoidCamera],
    positions: ArrayLike,
    visible: ArrayLike,
    sigma: float = PIXEL_SIGMA,
    settings: TrackerSettings = DEFAULT_SETTINGS,
) -> Array:
    """The PCRB's position block ``(T, 3, 3)`` (m^2) along one run's true positions ``(T, 3)``,
    with camera ``n`` informative at step ``t`` where ``visible[t, n]`` and never at step 0.

    The motion is the trackers' constant velocity; its velocity enters the bound only through
    the prior (a linear model: the Jacobians are the same whatever the true velocity)."""
    x, seen = _checked(positions, visible, len(cams))
    sensors = projections(cams, sigma)
    states = np.concatenate([x, np.zeros_like(x)], axis=-1)
    info = np.stack([s.fisher_information(states) for s in sensors], axis=1)  # (T, S, 6, 6)
    mask = seen.copy()
    mask[0] = False  # the trackers start from the prior and update from step 1
    J = posterior_information(
        trackers_motion(settings),
        sensors,
        states,
        1.0,
        PRIOR_SD**2 * np.eye(STATE_DIM),
        mask=mask,
        information=info,
    )
    return np.asarray(np.linalg.inv(J)[:, :3, :3])


def run_bound(
    cams: Sequence[EllipsoidCamera],
    positions: ArrayLike,
    velocity0: ArrayLike,
    visible: ArrayLike,
    sigma: float = PIXEL_SIGMA,
) -> dict[str, Array]:
    """Per step ``(T,)``: the bound's ``trace B[pos]`` (m^2), its mean-error bound ``E|N(0,
    B[pos])|`` (m) and the trivial estimator's error ``|x_0 + t v_0 - x_t|`` (m)."""
    x, _ = _checked(positions, visible, len(cams))
    B = position_bound(cams, x, visible, sigma)
    t = np.arange(len(x))[:, None]
    trivial = x[0] + t * np.asarray(velocity0, dtype=float)
    return {
        "pcrb_mse": np.trace(B, axis1=-2, axis2=-1),
        "pcrb_mean": expected_norm(B),
        "trivial_err": np.linalg.norm(trivial - x, axis=-1),
    }


def with_bound(
    rows: Sequence[Mapping[str, Any]],
    cams: Sequence[EllipsoidCamera],
    positions: ArrayLike,
    velocity0: ArrayLike,
    visible: ArrayLike,
) -> list[dict[str, Any]]:
    """``rows`` (one per tracker and step ``t``) with the step's :data:`BOUND_COLUMNS`."""
    per_step = run_bound(cams, positions, velocity0, visible)
    return [{**r, **{k: float(v[int(r["t"])]) for k, v in per_step.items()}} for r in rows]


# --------------------------------------------------------------------------------------------
# beside the reports' tables


def has_bound(df: pd.DataFrame) -> bool:
    """Whether the rows carry the bound (rows recorded before it was added do not)."""
    return all(c in df.columns for c in BOUND_COLUMNS)


def bound_table(
    df: pd.DataFrame,
    trackers: Sequence[str],
    run: Sequence[str] = ("run",),
    by: Sequence[str] = (),
) -> pd.DataFrame:
    """Per group ``by`` and tracker: its mean and RMS 3-D error (± s.e.) over runs (each run's
    mean over its steps first), the mean-error bound and the PCRB RMS over the same runs and
    steps, their ratios, and the trivial estimator's mean error. Index: ``(*by, tracker)``."""
    d = df[df.tracker.isin(list(trackers)) & np.isfinite(df.err3d)].assign(sq=df.err3d**2)
    cols = ["err3d", "sq", *BOUND_COLUMNS]
    per_run = d.groupby([*by, *run, "tracker"])[cols].mean().reset_index()
    rows = []
    for key, g in per_run.groupby([*by, "tracker"]):
        rms, se = rms_over_runs(np.sqrt(g["sq"].to_numpy()))
        bound_rms = float(np.sqrt(g["pcrb_mse"].mean()))
        bound_mean = float(g["pcrb_mean"].mean())
        mean = float(g["err3d"].mean())
        keys = key if isinstance(key, tuple) else (key,)
        rows.append(
            {
                **dict(zip([*by, "tracker"], keys)),
                "mean 3-D error (m)": mean,
                "mean-error bound (m)": bound_mean,
                "mean / bound": mean / bound_mean,
                "RMS 3-D error (m)": rms,
                "s.e.": se,
                "PCRB RMS (m)": bound_rms,
                "RMS / PCRB": rms / bound_rms,
                "trivial mean error (m)": float(g["trivial_err"].mean()),
            }
        )
    out = pd.DataFrame(rows).set_index([*by, "tracker"])
    order = {k: i for i, k in enumerate(trackers)}
    return out.sort_index(key=lambda ix: ix.map(order) if ix.name == "tracker" else ix)


def _above(row: pd.Series) -> bool:
    se = float(row["s.e."]) if np.isfinite(row["s.e."]) else 0.0
    return bool(
        row["mean / bound"] >= 1.0
        and row["RMS 3-D error (m)"] >= row["PCRB RMS (m)"] - MARGIN_SE * se
    )


def above_claim(kinds: ClaimKinds, claim_id: str, table: pd.DataFrame, setting: str) -> Claim:
    """Diagnostic: every tracker's (and group's) mean 3-D error is above the mean-error bound
    and its RMS error not more than :data:`MARGIN_SE` standard errors below the PCRB RMS. Fails
    if a tracker beats the idealised pixel-exact detector on the trackers' own motion model (a
    wrong bound, or a tracker using knowledge of the path or sub-pixel evidence the bound's
    detector lacks)."""
    return kinds.claim(
        claim_id,
        f"{setting}: every tracker's 3-D error lies above the best possible, the PCRB of a "
        f"pixel-exact centre detector (sd {PIXEL_SIGMA:.3g} px) with the trackers' "
        "constant-velocity model along the runs' truths and visibility; ours: smallest error / "
        "bound",
        "no number (Ch. V gives figures only)",
        {
            "mean / bound": round(float(table["mean / bound"].min()), 3),
            "RMS / PCRB": round(float(table["RMS / PCRB"].min()), 3),
        },
        f"mean >= mean-error bound and RMS >= PCRB RMS - {MARGIN_SE:g} s.e., every tracker",
        all(_above(r) for _, r in table.iterrows()),
    )


def bound_row(df: pd.DataFrame, run: Sequence[str] = ("run",)) -> dict[str, float]:
    """The bound and the trivial estimator as rows of a mean-error table: mean over runs of each
    run's mean over its steps (one tracker's rows: every tracker has the same steps)."""
    one = df[df.tracker == df.tracker.iloc[0]]
    per_run = one.groupby(list(run))[["pcrb_mean", "trivial_err"]].mean()
    return {
        LABELS["pcrb"]: float(per_run["pcrb_mean"].mean()),
        LABELS["trivial"]: float(per_run["trivial_err"].mean()),
    }


def section(table: pd.DataFrame, claim_id: str) -> str:
    """The report's section: what the bound is for and every tracker beside it."""
    return f"""
## The best possible (PCRB)

What no tracker can beat (issue 19): the posterior Cramér-Rao bound of the 3-D position for an
idealised detector that reports the pixel of the target's centre in every camera that sees it
(at least {MIN_PIXELS} target pixels, not occluded), with Gaussian noise of sd 1/sqrt(12) =
{PIXEL_SIGMA:.3f} px, the spread of rounding to the pixel: a pixel-exact detector ([C]: the
dissertation and the spec give no measurement noise for Ch. V; at 1 px the bound is up to 3.4
times higher, and no floor: the trackers' 2-D reprojection errors are about a pixel), with the
trackers' own constant-velocity model (q = {DEFAULT_SETTINGS.kf_q:g} m^2/step^3, one step per
frame) and their manual initialisation (sd {PRIOR_SD:g} m and m/step about the truth at step 0),
evaluated along each run's own truth (Tichavský et al. 1998). The trackers do not see a point but
score appearance histograms, so this is the floor of a pixel-exact detector on the model they
assume, not of the images' full information; the truths are smooth paths, not draws from that
model.

The PCRB bounds the mean square error: "RMS" is the root of the mean over runs of each run's
mean square 3-D error (± its s.e.) against the root of the mean trace of the bound's position
block. "mean-error bound" is the mean of E|N(0, B_k)| over the same steps, the floor of a mean
Euclidean error if each step's error is centred Gaussian with covariance at least the bound.
"trivial" is the manual initialisation extrapolated at constant velocity (no camera).
`{claim_id}` checks that every tracker is above the bound. The dissertation prints no number
for Ch. V, so no paper number is judged here.

{table.reset_index().to_markdown(index=False, floatfmt=".3g")}
"""


__all__ = [
    "BOUND_COLUMNS",
    "LABELS",
    "MIN_PIXELS",
    "PIXEL_SIGMA",
    "PRIOR_SD",
    "PointProjection",
    "above_claim",
    "bound_row",
    "bound_table",
    "has_bound",
    "position_bound",
    "projections",
    "run_bound",
    "section",
    "trackers_motion",
    "with_bound",
]
