"""What no tracker can beat on Nott 2009's simulation model (issue 19, item 3): the PCRB beside
the simulation's tables, and the claims that check our trackers and the spec's [PROTO]
magnitudes against it.

**The bound.** The posterior Cramér-Rao bound (Tichavský, Muravchik & Nehorai 1998) of the
model the runs simulate (:mod:`.scenario`), on the sensors' state ``[x, y, h, w, vx, vy]``:

* motion: the foot's white acceleration of ``sigma_a_truth`` applied as
  ``pos += v dt + a dt^2 / 2, vel += a dt`` (Wiener-sequence noise of rank 2; the height and
  the width have none), i.e. :class:`~fusetrack.motion.WalkingPerson` with ``q_a =
  sigma_a_truth`` and ``q_h = q_w = 0``. The singular noise takes the PCRB's covariance form
  (:mod:`fusetrack.evaluation.crlb`). The deterministic acceleration of the "ca" cases and
  the width's sinusoid are known inputs: a known input adds no information and moves every
  state by a known amount, so it leaves the bound unchanged; an estimator told it can only do
  better than one that is not, so the bound holds for our trackers, which are not told it;
* sensors: the tag (:class:`~fusetrack.sensors.PositionFix`) on its reporting frames, the
  camera (:class:`~fusetrack.sensors.HomographyCamera`, Fisher information ``D^T R^-1 D`` of its
  analytic Jacobian at the true state) outside the occlusion window, both from step 0;
* prior: ``x_0 ~ N(true start, P0)`` with the trackers' ``P0 = diag(1, 1, 0.01, 0.04, 1, 1)``
  (:func:`.scenario.prior`), before the step-0 reports: the bound is for estimators that know
  the start no better than the trackers. The runs start from a fixed state, which an estimator
  told it could exploit; the bound after the burn-in moves little with the prior (``P0 x 10``
  and ``P0 / 100`` in :data:`PRIOR_CASES`), which the report shows (claim
  ``BP_prior_negligible``);
* the expectation over truths is the Monte Carlo average over the runs' own trajectories
  (re-simulated from the runs' seeds, checked against the recorded true positions).

Tag reports on their own jittered clock (the event-mode clock-offset cases) fall between the
frames, where the bound's state is not defined; those cases have no bound here.

**Comparisons.** The bound bounds the mean square error, so trackers are compared by their root
mean square error over runs and steps (``sqrt`` of the mean over runs of the per-run mean square
error, :func:`~fusetrack.evaluation.rms_over_runs`) with ``sqrt(mean_k trace(B_k[pos]))``. A mean
Euclidean error (the report's metric, and the spec's [PROTO] numbers) can lie below an RMS bound,
and no mean-square bound bounds it without an assumption on the error's distribution. With the
assumption that each step's error is Gaussian and centred with covariance at least ``B_k`` (exact
for a Kalman filter on a linear-Gaussian model, close for these EKFs), ``E|e_k| >= E|N(0,
B_k[pos])|`` (Jensen: adding independent noise cannot lower an expected norm), and
``E|N(0, C)| = sqrt(2 / pi) s_1 E(1 - s_2^2 / s_1^2)`` with ``s_1 >= s_2`` the standard deviations
along ``C``'s axes and ``E`` the complete elliptic integral of the second kind
(:func:`~fusetrack.evaluation.expected_norm`). That mean-error bound is what a [PROTO] mean
error is compared with.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from ...core import ConfigError, invalid
from ...evaluation import (
    IMPOSSIBLE,
    MARGIN_SE,
    POSSIBLE,
    Claim,
    ClaimKinds,
    best_possible_verdict,
    best_table,
    expected_norm,
    posterior_crlb,
    rms_over_runs,
)
from ...motion import WalkingPerson
from .scenario import SimConfig, sensors, simulate_truth

Array = np.ndarray
PRIOR_COV = np.diag([1.0, 1.0, 0.01, 0.04, 1.0, 1.0])
"""The bound's prior covariance about the true start: the trackers' ``P0``."""
PRIOR_SCALES = (10.0, 0.01)
"""The prior check: the bound with ``P0`` times each of these against the bound with ``P0``."""
PRIOR_CASES = ("S1", "rate-k15")
"""Cases the prior check runs on (two more bounds each): the camera throughout, and the least
information (a 15-step occlusion with the tag every 15th frame)."""
PRIOR_TOLERANCE = 0.05
"""Largest relative change of an RMS bound under :data:`PRIOR_SCALES` that counts as negligible."""
SPANS = {"run": "after burn-in", "window": "occlusion window"}
TRACKER_FIELDS = ("stacked", "filter_model", "q_a", "q_h", "q_w")
"""Fields of :class:`.scenario.SimConfig` only the trackers read: cases that differ in these
alone share one bound."""


def truth_motion(cfg: SimConfig) -> WalkingPerson:
    """The truth's motion without its known inputs: white foot acceleration ``sigma_a_truth``
    (Wiener sequence), constant height and width."""
    return WalkingPerson(q_a=cfg.sigma_a_truth, q_h=0.0, q_w=0.0, step=cfg.dt)


def report_mask(cfg: SimConfig) -> Array:
    """``(T, 2)`` booleans: the tag (every ``rfid_every``-th frame from 0) and the camera (not in
    the occlusion window) report at each frame, in the order of :func:`bound_sensors`."""
    if cfg.mode != "grid":
        raise ConfigError(invalid("mode", cfg.mode, "'grid' (the tag on the frame clock)"))
    tag = np.arange(cfg.n_steps) % cfg.rfid_every == 0
    return np.column_stack([tag, ~cfg.occluded()])


def bound_sensors(cfg: SimConfig) -> list[Any]:
    """The tag and the camera of the runs, in the order of :func:`report_mask`'s columns."""
    sens = sensors(cfg)
    return [sens["tag"], sens["camera"]]


def truths(cfg: SimConfig, seeds: Sequence[int]) -> Array:
    """``(R, T, 6)``: the runs' true states, re-simulated from their seeds as
    :func:`.scenario.run_once` does (the truth is the first draw of the run's generator)."""
    return np.stack([simulate_truth(cfg, np.random.default_rng(int(s))) for s in seeds])


def sensor_information(cfg: SimConfig, x: Array) -> Array:
    """Each sensor's Fisher information ``H^T R^-1 H`` at the truths ``x`` ``(R, T, 6)``, in one
    call over all frames: ``(R, T, 2, 6, 6)`` in the order of :func:`bound_sensors`."""
    return np.stack([s.fisher_information(x) for s in bound_sensors(cfg)], axis=2)


def pcrb_positions(
    motion: Any,
    sensors_: Sequence[Any],
    x: Array,
    dt: float,
    mask: Array,
    prior_cov: Array = PRIOR_COV,
    information: Array | None = None,
) -> Array:
    """The PCRB's position block at every frame, ``(T, 2, 2)`` (m^2), of ``motion`` and
    ``sensors_`` (reporting where ``mask`` ``(T, S)`` or ``(R, T, S)`` is true) along truths ``x``
    ``(R, T, d)`` with positions first, from the prior ``N(true start, prior_cov)``
    (:func:`~fusetrack.evaluation.posterior_crlb`; covariance form for a singular noise)."""
    B = posterior_crlb(motion, list(sensors_), x, dt, prior_cov, mask=mask, information=information)
    return np.asarray(B[:, :2, :2])


def position_bound(
    cfg: SimConfig, x: Array, prior_scale: float = 1.0, information: Array | None = None
) -> Array:
    """The PCRB's position block at every frame, ``(T, 2, 2)`` (m^2), along truths ``x``
    (``information``: :func:`sensor_information` at ``x``, computed here when None)."""
    return pcrb_positions(
        truth_motion(cfg),
        bound_sensors(cfg),
        x,
        cfg.dt,
        report_mask(cfg),
        prior_scale * PRIOR_COV,
        sensor_information(cfg, x) if information is None else information,
    )


def span_bounds(
    pos: Array, spans: Mapping[str, Array]
) -> tuple[dict[str, float], dict[str, float]]:
    """Per span (frames ``spans[name]``, booleans ``(T,)``), from the bound's position blocks
    ``pos`` ``(T, 2, 2)``: the RMS bound ``sqrt(mean_k trace B_k[pos])`` and the Gaussian
    mean-error bound ``mean_k E|N(0, B_k[pos])|`` (m)."""
    mse = np.trace(pos, axis1=-2, axis2=-1)
    return (
        {span: float(np.sqrt(mse[s].mean())) for span, s in spans.items()},
        {span: float(expected_norm(pos[s]).mean()) for span, s in spans.items()},
    )


@dataclass(frozen=True)
class ModelBound:
    """The bound of one simulated model along its runs' truths, per span (``"run"``: after the
    burn-in; ``"window"``: the occluded frames among those, if any): the RMS bound
    ``sqrt(mean_k trace B_k[pos])`` and the Gaussian mean-error bound ``mean_k E|N(0,
    B_k[pos])|`` (m); and the largest relative change of the RMS bound under
    :data:`PRIOR_SCALES` (NaN when not checked)."""

    rms: dict[str, float]
    mean: dict[str, float]
    prior_change: float


@dataclass(frozen=True)
class CaseBound:
    """One case: its model's :class:`ModelBound` and, per span, each method's RMS error over
    runs ``(value, s.e.)`` and mean error (m)."""

    case: str
    bound: ModelBound
    rms: dict[str, dict[str, tuple[float, float]]]
    mean: dict[str, dict[str, float]]

    @property
    def spans(self) -> list[str]:
        return list(self.bound.rms)

    def best_method(self, span: str) -> str:
        """The method with the lowest RMS error in ``span``."""
        return min(self.rms[span], key=lambda m: self.rms[span][m][0])


def spans_of(cfg: SimConfig, burn_in: int) -> dict[str, Array]:
    """Frames of each span: after the burn-in, and the occluded ones among them (if any)."""
    after = np.arange(cfg.n_steps) >= burn_in
    spans = {"run": after}
    if (cfg.occluded() & after).any():
        spans["window"] = cfg.occluded() & after
    return spans


def model_bound(cfg: SimConfig, x: Array, burn_in: int, check_prior: bool) -> ModelBound:
    """:class:`ModelBound` of ``cfg``'s model along truths ``x`` ``(R, T, 6)``; with
    ``check_prior`` also with ``P0`` scaled by each of :data:`PRIOR_SCALES`."""
    info = sensor_information(cfg, x)
    pos = position_bound(cfg, x, information=info)
    mse = np.trace(pos, axis1=-2, axis2=-1)
    spans = spans_of(cfg, burn_in)
    change = float("nan")
    if check_prior:
        change = 0.0
        for scale in PRIOR_SCALES:
            other = np.trace(position_bound(cfg, x, scale, info), axis1=-2, axis2=-1)
            for s in spans.values():
                change = max(change, abs(float(np.sqrt(other[s].mean() / mse[s].mean())) - 1))
    return ModelBound(*span_bounds(pos, spans), change)


SpanErrors = tuple[dict[str, tuple[float, float]], dict[str, float]]


def tracker_errors(df: pd.DataFrame, burn_in: int) -> dict[tuple[str, str], SpanErrors]:
    """Per case and span (after the burn-in; the window: the occluded frames among those):
    each method's RMS error over runs ``(value, s.e.)`` (:func:`rms_over_runs` of the per-run
    RMS over the span's frames) and its mean error over runs and frames (m)."""
    d = df[df["step"] >= burn_in].assign(sq=lambda x: x["err"] ** 2)
    keys = ["case", "method", "run"]
    per_run = pd.concat(
        [
            d.groupby(keys)[["sq", "err"]].mean().assign(span="run"),
            d[d["occluded"]].groupby(keys)[["sq", "err"]].mean().assign(span="window"),
        ]
    ).reset_index()
    out: dict[tuple[str, str], SpanErrors] = {}
    for (case, span, method), g in per_run.groupby(["case", "span", "method"]):
        rms, mean = out.setdefault((str(case), str(span)), ({}, {}))
        rms[str(method)] = rms_over_runs(np.sqrt(g["sq"].to_numpy()))
        mean[str(method)] = float(g["err"].mean())  # equal frames per run: the rows' mean
    return out


def case_bound(
    case: str, bound: ModelBound, errors: Mapping[tuple[str, str], SpanErrors]
) -> CaseBound:
    """One case's :class:`CaseBound` from its model's bound and :func:`tracker_errors`."""
    spans = list(bound.rms)
    return CaseBound(
        case,
        bound,
        {span: errors[(case, span)][0] for span in spans},
        {span: errors[(case, span)][1] for span in spans},
    )


def _case_truths(cfg: SimConfig, j: pd.DataFrame) -> Array:
    """The runs' truths ``(R, T, 6)`` from the joint EKF's rows ``j`` of one case (their seeds),
    checked against the true positions the runs recorded."""
    j = j.sort_values(["run", "step"])
    seeds = j.groupby("run")["seed"].first().to_list()
    x = truths(cfg, seeds)
    recorded = j[["true_x", "true_y"]].to_numpy().reshape(len(seeds), cfg.n_steps, 2)
    if not np.allclose(x[..., :2], recorded, rtol=0, atol=1e-12):
        raise RuntimeError("re-simulated truths differ from the runs' recorded true positions")
    return x


def estimate(
    df: pd.DataFrame, configs: Sequence[Mapping[str, Any]], burn_in: int
) -> dict[str, CaseBound]:
    """:class:`CaseBound` of every grid-mode configuration (event-mode cases have none);
    cases whose truths, sensors and runs are the same (they differ in their trackers only,
    :data:`TRACKER_FIELDS`) share one bound."""
    errors = tracker_errors(df, burn_in)
    j = df[df["method"] == "J"]
    out: dict[str, CaseBound] = {}
    bounds: dict[tuple[SimConfig, tuple[int, ...]], ModelBound] = {}
    for c in configs:
        cfg, case = SimConfig.from_mapping(c), str(c["case"])
        if cfg.mode != "grid":
            continue
        jc = j[j["case"] == case]
        seeds = tuple(int(s) for s in jc.groupby("run")["seed"].first())
        key = (replace(cfg, **{f: getattr(SimConfig(), f) for f in TRACKER_FIELDS}), seeds)
        if key not in bounds:
            x = _case_truths(cfg, jc)
            bounds[key] = model_bound(cfg, x, burn_in, case in PRIOR_CASES)
        out[case] = case_bound(case, bounds[key], errors)
    return out


def _above(cb: CaseBound, span: str, method: str = "J") -> bool:
    """``method``'s RMS is not more than :data:`MARGIN_SE` standard errors below the bound."""
    value, se = cb.rms[span][method]
    return bool(value >= cb.bound.rms[span] - MARGIN_SE * (se if np.isfinite(se) else 0.0))


def above_claims(
    kinds: ClaimKinds,
    bounds: Mapping[str, CaseBound],
    spans: Mapping[str, str] = SPANS,
    model: str = "simulated model",
) -> list[Claim]:
    """Diagnostic per case: the joint EKF's RMS error is not below the PCRB of ``model`` (in
    each span, named by ``spans``). Fails only if the tracker or the bound is wrong, or (on
    data not drawn from ``model``) the data carry more information than ``model``."""
    out = []
    for case, cb in bounds.items():
        ratios = {span: cb.rms[span]["J"][0] / cb.bound.rms[span] for span in cb.spans}
        out.append(
            kinds.claim(
                f"BP_J_above_bound_{case}",
                f"{case}: the joint EKF's RMS position error is not below the PCRB of the "
                f"{model} ({' and '.join(spans[s] for s in cb.spans)}); ours: RMS / bound",
                "not in the thesis",
                float(min(ratios.values())),
                f"RMS >= bound - {MARGIN_SE:g} s.e. in every span",
                all(_above(cb, span) for span in cb.spans),
            )
        )
    return out


def proto_rows(
    bounds: Mapping[str, CaseBound], proto: Mapping[str, Mapping[str, float]]
) -> pd.DataFrame:
    """Every [PROTO] mean error beside the Gaussian mean-error bound of its case and span
    (whole run for cases without occlusion, else the window, as the report's tables)."""
    rows = []
    for case, values in proto.items():
        cb = bounds[case]
        span = "window" if "window" in cb.bound.rms else "run"
        for method, paper in values.items():
            b = cb.bound.mean[span]
            rows.append(
                {
                    "case": case,
                    "span": SPANS[span],
                    "method": method,
                    "[PROTO] mean (m)": paper,
                    "ours mean (m)": cb.mean[span][method],
                    "mean-error bound (m)": b,
                    "verdict": best_possible_verdict(paper, b, float("nan")),
                }
            )
    return pd.DataFrame(rows)


def proto_claims(kinds: ClaimKinds, rows: pd.DataFrame) -> list[Claim]:
    """Diagnostic per case: the spec's [PROTO] joint-EKF mean error is not below the mean-error
    bound (Gaussian errors assumed); the occlusion sweep's six lengths in one claim."""
    j = rows[rows["method"] == "J"]
    groups = [(c, j[j["case"] == c]) for c in j["case"].unique() if not c.startswith("sweep-")]
    groups.append(("sweep", j[j["case"].str.startswith("sweep-")]))
    out = []
    for name, g in groups:
        if g.empty:
            continue
        ratio = (g["[PROTO] mean (m)"] / g["mean-error bound (m)"]).to_numpy()
        ok = bool((g["verdict"] == POSSIBLE).all())
        out.append(
            kinds.claim(
                f"BP_PROTO_J_possible_{name}",
                f"{name}: the spec's [PROTO] joint-EKF mean error is not below the mean-error "
                "bound of the simulated model (PCRB, Gaussian errors); ours: [PROTO] / bound"
                + (" (smallest over L)" if len(g) > 1 else ""),
                ", ".join(f"{v:.3f}" for v in g["[PROTO] mean (m)"]),
                float(ratio.min()),
                f">= 1 ({POSSIBLE}), else {IMPOSSIBLE}",
                ok,
            )
        )
    return out


def prior_claim(kinds: ClaimKinds, bounds: Mapping[str, CaseBound]) -> Claim:
    """Diagnostic: after the burn-in the bound barely depends on its prior."""
    checked = [cb for cb in bounds.values() if np.isfinite(cb.bound.prior_change)]
    worst = max(checked, key=lambda cb: cb.bound.prior_change)
    scales = " and ".join(f"x {s:g}" for s in PRIOR_SCALES)
    return kinds.claim(
        "BP_prior_negligible",
        f"the PCRB's RMS after the burn-in changes little when its prior P0 is scaled by {scales} "
        f"(largest relative change over {', '.join(cb.case for cb in checked)} and their spans)",
        "not in the thesis",
        worst.bound.prior_change,
        f"< {PRIOR_TOLERANCE:g}",
        worst.bound.prior_change < PRIOR_TOLERANCE,
    )


def table(bounds: Mapping[str, CaseBound], spans: Mapping[str, str] = SPANS) -> pd.DataFrame:
    """Per case and span (named by ``spans``): J's RMS (± s.e.), the RMS bound, their ratio,
    and the best tracker."""
    rows: dict[str, dict[str, Any]] = {}
    for case, cb in bounds.items():
        for span in cb.spans:
            value, se = cb.rms[span]["J"]
            best = cb.best_method(span)
            rows[f"{case} ({spans[span]})"] = {
                "J RMS (m)": value,
                "s.e.": se,
                "PCRB RMS (m)": cb.bound.rms[span],
                "J / PCRB": value / cb.bound.rms[span],
                "best tracker": best,
                "best RMS (m)": cb.rms[span][best][0],
                "best / PCRB": cb.rms[span][best][0] / cb.bound.rms[span],
            }
    return best_table(rows).rename_axis("case").reset_index()


def report(bounds: Mapping[str, CaseBound], proto: pd.DataFrame, runs: int, burn_in: int) -> str:
    """Report text: the bound per case beside our trackers, and the [PROTO] numbers against it."""
    checked = [cb for cb in bounds.values() if np.isfinite(cb.bound.prior_change)]
    change = max(cb.bound.prior_change for cb in checked)
    scales = " and ".join(f"{s:g}" for s in PRIOR_SCALES)
    return f"""
## The best possible on the simulated model

What no tracker can beat (issue 19): the posterior Cramér-Rao bound (PCRB, Tichavský et al.
1998, in the covariance form for the truth's rank-2 Wiener-sequence acceleration noise) of the
model the runs simulate, on the state [x, y, h, w, vx, vy], along the {runs} runs' own truths:
tag on its reporting frames, camera (V8 or V4, 1 px) outside the occlusion window, known
deterministic acceleration and width sinusoid (known inputs leave the bound unchanged and an
estimator told them can only do better, so the bound holds for our trackers), prior
N(true start, P0) with the trackers' P0 = diag(1, 1, 0.01, 0.04, 1, 1). Scaling P0 by {scales}
moves the RMS bound after the {burn_in}-step burn-in by at most {change:.2%} in
{", ".join(cb.case for cb in checked)} (claim `BP_prior_negligible`). Cases that differ only in
their trackers (S4-ca, S4-ca-CAfilter, rate-k1) share one bound; the event-mode clock-offset
cases (tag reports between the frames) have none.

A mean-square bound bounds the root mean square error, so the trackers appear here by their RMS
position error (root of the mean over runs of each run's mean square error over the steps; ± its
standard error) against sqrt(mean over the same steps of the trace of the bound's position
block). `BP_J_above_bound_*` check that the joint EKF is not more than {MARGIN_SE:g} standard
errors below it (a failure would mean a wrong tracker or a wrong bound; with a single run there
is no standard error and no margin, and one run's error may well fall below a bound on the
average); "best" is the lowest RMS among B1-B5 and J.

{best_table_md(table(bounds))}

The spec's [PROTO] numbers are mean Euclidean errors, which can lie below an RMS bound; no
mean-square bound bounds a mean error without assuming the error's distribution. Assuming each
step's error is centred Gaussian with covariance at least the bound (exact for a Kalman filter on
a linear-Gaussian model), E|e_k| >= E|N(0, B_k)| = sqrt(2/pi) s1 E(1 - s2^2/s1^2) (s1 >= s2 the
bound's standard deviations along its axes, E the complete elliptic integral of the second kind);
its mean over the same steps is the mean-error bound below. A [PROTO] number under it is
*{IMPOSSIBLE}* (under that assumption); `BP_PROTO_J_possible_*` check the joint EKF's.

{best_table_md(proto)}

"""


def best_table_md(df: pd.DataFrame) -> str:
    return str(df.to_markdown(index=False, floatfmt=".3g"))


__all__ = [
    "IMPOSSIBLE",
    "POSSIBLE",
    "PRIOR_COV",
    "CaseBound",
    "ModelBound",
    "above_claims",
    "bound_sensors",
    "case_bound",
    "estimate",
    "expected_norm",
    "model_bound",
    "pcrb_positions",
    "position_bound",
    "prior_claim",
    "proto_claims",
    "proto_rows",
    "report",
    "report_mask",
    "span_bounds",
    "spans_of",
    "table",
    "tracker_errors",
    "truth_motion",
    "truths",
]
