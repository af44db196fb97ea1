"""Lee 2009, Ch. 3: acoustic multi-object tracking with periodic or triggered camera cooperation.

Parts (spec 000, Sec. 5.5):

* E3.1 -- acoustic only, bearing-noise sweep sigma^2 = 0, 0.5, 1.5, 5 deg^2 (Fig. 3-4; C7);
* E3.2 -- periodic camera updates, T_v sweep (Figs. 3-5, 3-6; C8);
* E3.4 -- the E3.3 environment (sensor at (25, 25), objects entering and leaving): no cooperation,
  combined triggering, each trigger removed, and periodic T_v (Table 3.1, Fig. 3-14; C9, C10);
* E3.5 -- the indoor room, two acoustic sensors, triggering probabilities with and without
  cooperation (Figs. 3-15 ... 3-21; C11);
* readings of what the text leaves open (:data:`READINGS`, :data:`VELOCITIES_31`): E3.1 with
  velocities whose bearings never merge, alpha = 0.01 m/s^2, and the printed estimator; C7, C9,
  C10 judged under each;
* the best possible beside E3.1, E3.2 and Table 3.1 (issue 19, item 3): the CRLB of each object's
  position on the simulated model, per run from its own camera steps (:mod:`.bearing_bound`),
  our filters checked against it and the paper's numbers judged on it (:mod:`.best_possible`;
  ``BP_*`` claims, kind diagnostic).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from pydantic import Field, field_validator

from ...evaluation import (
    Claim,
    ClaimKinds,
    ExperimentOptions,
    Outcome,
    RunContext,
    interval_values,
    paired_interval,
    plots,
    shown_positive,
)
from ...filters import turn_models
from ...management import AcousticTracker, CooperationPolicy, run_cooperation, run_periodic_batch
from . import best_possible as bp
from .bearing_bound import periodic_bound_ms, run_bound_ms, step_alphas, step_model, turn_alpha

DEG = math.pi / 180.0
T_33 = 200
ALPHA_33 = 1.0  # one-step turns (spec Sec. 9 item 19)
SIGMA_A_33 = 0.01
PAPER_E31 = (3.98, 9.80, 1.08)
PAPER_T31 = {"none": (7.54, 3.70, 5.54, 5.59), "trig": (1.38, 0.24, 0.32, 0.64)}
PAPER_TV_EQUIV = (4.16, 4.28, 4.19, 4.21)
PAPER_TV_TRIG = 4.55
SWEEP_PERIODS = [1, 3, 10, 30, 100]  # E3.2 camera periods (T_s) run at 1,000 trials


class SweepOptions(ExperimentOptions):
    """``fusetrack run lee2009-periodic-sweep`` options."""

    periods: tuple[int, ...] | None = Field(
        None,
        description="camera periods T_v to sweep, e.g. 1,10,100 "
        f"(default: 1,10,100 with --quick, else {','.join(map(str, SWEEP_PERIODS))})",
    )

    @field_validator("periods", mode="before")
    @classmethod
    def _split(cls, v: Any) -> Any:
        return [p.strip() for p in v.split(",")] if isinstance(v, str) else v

    @field_validator("periods")
    @classmethod
    def _two_or_more(cls, v: tuple[int, ...] | None) -> tuple[int, ...] | None:
        if v is not None and (len(set(v)) < 2 or min(v) < 1):
            raise ValueError("two or more integers >= 1, e.g. 1,10,100")
        return None if v is None else tuple(sorted(set(v)))


def piecewise_truth(
    x0: np.ndarray, schedule: Sequence[Sequence[tuple[float, float, float]]], dt: float, steps: int
) -> np.ndarray:
    """``(steps, O, 4)``: object ``o`` follows ``schedule[o]`` = [(t_start, t_end, alpha)] (alpha 0 = CV)."""
    out = np.zeros((steps, len(x0), 4))
    out[0] = x0
    for k in range(1, steps):
        for o, sched in enumerate(schedule):
            out[k, o] = step_model(turn_alpha(sched, (k - 1) * dt)).mean(out[k - 1, o], dt)
    return out


def schedule_alphas(
    schedule: Sequence[Sequence[tuple[float, float, float]]], dt: float, steps: int
) -> np.ndarray:
    """``(steps - 1, O)``: the turn acceleration of each object's step ``k -> k + 1`` in
    :func:`piecewise_truth` (0: constant velocity)."""
    return np.stack([step_alphas(sched, dt, steps) for sched in schedule], axis=1)


# E3.1/E3.2 object velocities (the text gives none; Fig. 3-4(a) only draws the tracks):
# "spec" -- spec Sec. 5.5's choice, in which O2 and O3 meet (bearings within 2 deg for 70 of the
# 200 steps from k = 41, O1 and O2 for 18), so association errors swamp the noise trend;
# "apart" -- the same speeds' components, bearings never closer than 10 deg (their start).
VELOCITIES_31 = {
    "spec": ((-0.2, 0.1), (0.1, -0.2), (-0.1, -0.1)),
    "apart": ((0.2, -0.1), (-0.2, 0.1), (0.2, 0.1)),
}


@dataclass(frozen=True)
class Reading:
    """What Sec. 3.3 leaves open (spec Sec. 9 items 19, 23): the turn acceleration ``alpha``
    (1 m/s^2, or the bullet's 0.01 m/s^2) of the truth and the filter's CT/ACT models, and the
    estimator (the consistent JPDA average, or the printed chain (3.7)-(3.11), "literal")."""

    alpha: float = ALPHA_33
    estimator: str = "consistent"


READINGS = {
    "alpha=1": Reading(),
    "alpha=0.01": Reading(alpha=0.01),
    "printed": Reading(estimator="literal"),
}
DEFAULT_READING = "alpha=1"


def _read_only(*arrays: np.ndarray) -> None:
    """Freeze the cached truths (every run of a worker process shares them)."""
    for a in arrays:
        a.flags.writeable = False


def schedule_e31(alpha: float = ALPHA_33) -> list[list[tuple[float, float, float]]]:
    """E3.1/E3.2 turns: one-step turns at k = 51, 101, 151 (CT = -alpha, ACT = +alpha; spec
    choice of directions)."""
    signs = {51: (-1, 1, -1), 101: (1, -1, -1), 151: (-1, 1, 1)}
    return [[(k - 1.0, k, s[o] * alpha) for k, s in signs.items()] for o in range(3)]


@functools.cache
def truth_e31(scenario: str = "spec", alpha: float = ALPHA_33) -> np.ndarray:
    """E3.1/E3.2: O1 (50, 30), O2 (35, 50), O3 (45, 45), CV with one-step turns at k = 51, 101,
    151; velocities :data:`VELOCITIES_31` ``[scenario]``."""
    x0 = np.array([[50, 30], [35, 50], [45, 45]], float)
    x0 = np.hstack([x0, np.asarray(VELOCITIES_31[scenario], float)])
    truth = piecewise_truth(x0, schedule_e31(alpha), 1.0, T_33)
    _read_only(truth)
    return truth


def schedule_e33(alpha: float = ALPHA_33) -> list[list[tuple[float, float, float]]]:
    """E3.3/E3.4 turns: O1, O2 at k = 51, 101, 151; O3 turns from 100 to 150."""
    return [
        [(50.0, 51.0, -alpha), (100.0, 101.0, alpha), (150.0, 151.0, -alpha)],
        [(50.0, 51.0, alpha), (100.0, 101.0, -alpha), (150.0, 151.0, alpha)],
        [(100.0, 150.0, -alpha)],
    ]


@functools.cache
def truth_e33(alpha: float = ALPHA_33) -> tuple[np.ndarray, np.ndarray]:
    """E3.3/E3.4: sensor at (25, 25); O1 enters at 25, O2 leaves at 175, O3 present 63-187
    (computed once per process and alpha; read-only)."""
    x0 = np.array([[5, 3, 0.2, 0.2], [22, 3, -0.2, 0.2], [40, 12, -0.2, 0.15]], float)
    truth = piecewise_truth(x0, schedule_e33(alpha), 1.0, T_33)
    present = np.zeros((T_33, 3), bool)
    present[25:, 0] = True
    present[:175, 1] = True
    present[63:188, 2] = True
    _read_only(truth, present)
    return truth, present


# Indoor room (E3.5)
ROOM = (14.63, 8.23)
SENSORS_35 = {"A1": (3.2, 1.9), "A2": (7.6, 6.8)}
CAMERAS_35 = {"V1": (1.9, 6.3), "V2": (13.4, 5.0), "V3": (5.5, 0.3)}
DT_35, T_35 = 0.01, 1900


@functools.cache
def truth_e35() -> np.ndarray:
    """E3.5: the room's three objects (computed once per process; read-only)."""
    x0 = np.array([[2.9, 4.5, 0.0, -0.3], [4.8, 3.5, 0.3, -0.1], [5.1, 8.2, 0.0, 0.0]], float)
    sched = [
        [(3.6, 7.1, 0.15), (13.5, 15.0, 0.20)],
        [(4.5, 6.1, 0.45), (7.5, 8.5, 0.30), (8.5, 9.5, -0.30), (13.0, 16.0, -0.25)],
        [],
    ]
    tr = piecewise_truth(x0, sched, DT_35, T_35)
    k13 = round(13.0 / DT_35)
    tr[k13:, 2, 2:] = (0.0, -0.3)  # O3 starts moving at 13 s (speed not given: spec choice)
    for k in range(k13 + 1, T_35):
        tr[k, 2, :2] = tr[k - 1, 2, :2] + DT_35 * tr[k - 1, 2, 2:]
    _read_only(tr)
    return tr


def masks_e35(sensor: str) -> tuple[np.ndarray, np.ndarray]:
    """Visibility (in range) and audibility per step and object, as the text's events (corrected)."""
    present = np.zeros((T_35, 3), bool)
    if sensor == "A1":
        present[:1500, 0] = True
        present[1500:, 1] = True
        present[1600:, 2] = True
        audible = present.copy()
        audible[500:700, 0] = False  # O1 silent 5.0-7.0 s
    else:
        present[:, 1] = True
        present[1100:, 0] = True
        present[1300:, 2] = True
        audible = present.copy()
    return present, audible


def _policy(name: str) -> CooperationPolicy:
    if name == "none":
        return CooperationPolicy()
    if name == "trigger":
        return CooperationPolicy.triggering()
    if name.startswith("trigger without "):
        off = name.removeprefix("trigger without ")
        return CooperationPolicy(count=off != "count", gate=off != "gate", ellipse=off != "ellipse")
    if name.startswith("only "):
        on = name.removeprefix("only ")
        return CooperationPolicy(count=on == "count", gate=on == "gate", ellipse=on == "ellipse")
    if name.startswith("periodic "):
        return CooperationPolicy(period=int(name.split()[1]))
    raise ValueError(name)


def _object_rows(
    part: str,
    config: Mapping[str, Any],
    res: Any,
    truth: np.ndarray,
    bound_ms: np.ndarray | None = None,
) -> list[dict[str, Any]]:
    """One row per tracked object; ``bound_ms`` ``(O,)``: the CRLB on its mean square position
    error over its tracked steps in this run (:mod:`.bearing_bound`)."""
    rows = []
    for o in range(truth.shape[1]):
        tracked = res.tracked[:, o]
        if not tracked.any():
            continue
        err2 = np.sum((res.estimates[tracked, o, :2] - truth[tracked, o, :2]) ** 2, axis=-1)
        rows.append(
            {
                "part": part,
                "object": f"O{o + 1}",
                "rms": float(np.sqrt(err2.mean())),
                "tracked_steps": int(tracked.sum()),
                "camera_updates": int(res.camera_updates[:, o].sum()),
                "degenerate_steps": res.degenerate_steps,
            }
            | ({} if bound_ms is None else {"bound_ms": float(bound_ms[o])})
        )
    return rows


@functools.cache
def periodic_bound_e31(
    scenario: str, alpha: float, variance_deg2: float, period: int
) -> tuple[float, ...]:
    """E3.1/E3.2: each object's CRLB on its mean square position error over a run with cameras
    every ``period`` steps (0: none); the same for every run of the configuration (cached)."""
    truth = truth_e31(scenario, alpha)
    alphas = schedule_alphas(schedule_e31(alpha), 1.0, T_33)
    sigma = math.sqrt(variance_deg2) * DEG
    tracker = _tracker_33(1)
    ms = periodic_bound_ms(
        truth, alphas, 1.0, (0.0, 0.0), sigma, period, tracker.sigma_r, tracker.init_velocity_std
    )
    return tuple(float(m) for m in ms)


def _run_bound_e34(
    truth: np.ndarray, present: np.ndarray, alpha: float, res: Any, tracker: AcousticTracker
) -> np.ndarray:
    """E3.4: each object's CRLB on its mean square position error over its tracked steps in
    this run, from the run's own camera-use mask (:func:`.bearing_bound.run_bound_ms`)."""
    return run_bound_ms(
        truth, schedule_alphas(schedule_e33(alpha), 1.0, T_33), 1.0, (25.0, 25.0),
        math.sqrt(3.0) * DEG, res.tracked, present, res.camera_updates, tracker.sigma_r,
        tracker.init_velocity_std,
    )  # fmt: skip


def _tracker_33(
    n_particles: int, sigma: float | None = None, reading: Reading = READINGS[DEFAULT_READING]
) -> AcousticTracker:
    """The filter of Sec. 3.3 (E3.1-E3.4): known initial state, tight velocity prior; with the
    bearing std ``sigma`` the filter assumes at least 0.1 deg^2 of variance."""
    floor = None if sigma is None else max(sigma, math.sqrt(0.1) * DEG)
    return AcousticTracker(
        turn_models(reading.alpha, SIGMA_A_33), dt=1.0, n_particles=n_particles, sigma_filter=floor,
        known_initial_velocity=True, init_velocity_std=0.02, estimator=reading.estimator,
    )  # fmt: skip


def run_batch(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """E3.1/E3.2: ``trials`` runs for each camera period in ``periods`` (0 = none), as one batch.

    :func:`run_periodic_batch` has the law of :func:`run_cooperation` (tested); the batch axis
    makes the paper's 1,000-trial sweep affordable. The printed estimator has no batch form:
    its trials run one by one through :func:`run_cooperation`.
    """
    reading = READINGS[config.get("reading", DEFAULT_READING)]
    periods = np.repeat(np.asarray(config["periods"], int), int(config["trials"]))
    truth = truth_e31(config.get("scenario", "spec"), reading.alpha)
    sigma = math.sqrt(float(config["variance_deg2"])) * DEG
    rng = np.random.default_rng(seed)
    tracker = _tracker_33(int(config["n_particles"]), sigma, reading)
    if reading.estimator == "consistent":
        res = run_periodic_batch(truth, (0.0, 0.0), sigma, periods, rng, tracker)
        rms, updates, degenerate = (
            res.rms(truth),
            res.camera_updates.sum(axis=0),
            res.degenerate_steps,
        )
    else:
        rms, updates, degenerate = _trials_one_by_one(truth, sigma, periods, rng, tracker)
    first = int(config["chunk"]) * int(config["trials"])
    scenario, variance = config.get("scenario", "spec"), float(config["variance_deg2"])
    bounds = {
        int(tv): periodic_bound_e31(scenario, reading.alpha, variance, int(tv))
        for tv in set(periods.tolist())
    }
    return [
        {
            "part": config["part"],
            "policy": f"periodic {tv}" if tv else "none",
            "variance_deg2": float(config["variance_deg2"]),
            "n_particles": int(config["n_particles"]),
            "trial": first + b % int(config["trials"]),
            "object": f"O{o + 1}",
            "rms": float(rms[b, o]),
            "tracked_steps": T_33,
            "camera_updates": int(updates[b, o]),
            "degenerate_steps": degenerate,
            "bound_ms": bounds[int(tv)][o],
        }
        for b, tv in enumerate(periods)
        for o in range(truth.shape[1])
    ]


def _trials_one_by_one(
    truth: np.ndarray, sigma: float, periods: np.ndarray, rng: np.random.Generator,
    tracker: AcousticTracker,
) -> tuple[np.ndarray, np.ndarray, int]:  # fmt: skip
    """:func:`run_batch`'s ``(rms (B, O), camera updates (B, O), degenerate steps)``, one
    :func:`run_cooperation` per trial (every object present and audible throughout)."""
    present = np.ones(truth.shape[:2], bool)
    rms, updates, degenerate = [], [], 0
    for tv in periods:
        policy = CooperationPolicy(period=int(tv) if tv else None)
        res = run_cooperation(truth, present, present, (0.0, 0.0), sigma, policy, rng, tracker)
        err2 = np.sum((res.estimates[..., :2] - truth[..., :2]) ** 2, axis=-1)
        rms.append(np.sqrt(err2.mean(axis=0)))
        updates.append(res.camera_updates.sum(axis=0))
        degenerate += res.degenerate_steps
    return np.array(rms), np.array(updates), degenerate


def _batch_configs(
    part: str, variance: float, periods: list[int], trials: int, chunk: int, n: int, **keys: Any
) -> list[dict[str, Any]]:
    """Chunks of ``trials`` trials; ``keys`` (scenario, reading) ride along in each config."""
    return [
        {"part": part, "variance_deg2": variance, "periods": periods, "n_particles": n,
         "trials": min(chunk, trials - c * chunk), "chunk": c, **keys}
        for c in range(-(-trials // chunk))
    ]  # fmt: skip


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    rng = np.random.default_rng(seed)
    part = config["part"]
    n = int(config["n_particles"])
    if part in ("E3.1", "E3.2"):
        truth = truth_e31()
        present = np.ones((T_33, 3), bool)
        sigma = math.sqrt(float(config["variance_deg2"])) * DEG
        res = run_cooperation(
            truth, present, present, (0.0, 0.0), sigma, _policy(config["policy"]), rng,
            _tracker_33(n, sigma),
        )  # fmt: skip
        return _object_rows(part, config, res, truth)
    if part == "E3.4":
        reading = READINGS[config.get("reading", DEFAULT_READING)]
        truth, present = truth_e33(reading.alpha)
        policy, tracker = _policy(config["policy"]), _tracker_33(n, reading=reading)
        res = run_cooperation(
            truth, present, present, (25.0, 25.0), math.sqrt(3.0) * DEG, policy, rng, tracker
        )
        bound = _run_bound_e34(truth, present, reading.alpha, res, tracker)
        rows = _object_rows(part, config, res, truth, bound)
        rows.append(
            {
                "part": part,
                "object": "fired",
                "fired_count": int(res.fired[:, 0].sum()),
                "fired_gate": int(res.fired[:, 1].sum()),
                "fired_ellipse": int(res.fired[:, 2].sum()),
            }
        )
        return rows
    # E3.5: one sensor, with or without cooperation; per-step trigger flags
    truth = truth_e35()
    sensor = str(config["sensor"])
    present, audible = masks_e35(sensor)
    coop = bool(config["cooperation"])
    policy = CooperationPolicy.triggering(apply_fixes=coop)
    res = run_cooperation(
        truth, present, audible, SENSORS_35[sensor], math.sqrt(3.0) * DEG, policy, rng,
        AcousticTracker(turn_models(0.3, 0.1), DT_35, n, sigma_r=0.05, known_initial_velocity=True,
                        init_velocity_std=0.05),
        oracle_births=not coop,
    )  # fmt: skip
    rows = _object_rows(part, config, res, truth)
    fired = res.fired_any.astype(np.int8)
    rows.append(
        {
            "part": part,
            "object": "trigger_series",
            "fired_series": fired.tolist(),
            "count_series": res.fired[:, 0].astype(np.int8).tolist(),
        }
    )
    for o in range(3):
        if res.tracked[-1, o]:
            rows.append(
                {
                    "part": part,
                    "object": f"O{o + 1}",
                    "final_x": float(res.estimates[-1, o, 0]),
                    "final_y": float(res.estimates[-1, o, 1]),
                }
            )
    return rows


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "C7_*": "paper",
        "C8_*": "paper",
        "C9_*": "paper",
        "C10_*": "paper",
        "C11_*": "paper",
        "BP_*": "diagnostic",
    }
)


def _sweep_section(
    ctx: RunContext, e32: pd.DataFrame, tv_sweep: list[int]
) -> tuple[list[Claim], str]:
    """C8, the bound's check and the E3.2 report section (Figs. 3-5/3-6) from the per-trial
    rows of the sweep."""
    e32 = e32.assign(T_v=e32["policy"].str.split().str[1].astype(int))
    per_trial = e32.groupby(["T_v", "trial"])["rms"].mean()  # average over the three objects
    e32m = e32.groupby(["T_v", "object"])["rms"].mean().unstack("object")
    e32m["average"] = per_trial.groupby("T_v").mean()
    e32m["95% CI +-"] = (
        1.96 * per_trial.groupby("T_v").std(ddof=1) / np.sqrt(per_trial.groupby("T_v").size())
    )
    e32m["trials"] = per_trial.groupby("T_v").size()
    avg = e32m["average"]
    falls = bool(avg.loc[tv_sweep[0]] < avg.loc[tv_sweep[-1]])
    claim = CLAIM_KINDS.claim(
        "C8_periodic_falls",
        "periodic cooperation: average RMS at T_v = 1 below that at T_v = 100 (sigma^2 = 5), "
        f"{int(e32m['trials'].min())} trials per T_v",
        "error decreases as T_v -> T_s",
        {int(k): round(float(v), 3) for k, v in avg.items()},
        "RMS(1) < RMS(100)",
        falls,
    )
    fig, ax = plots.panel(size=(6, 4))
    plots.curves(ax, e32m.index, {c: e32m[c] for c in ("O1", "O2", "O3")})
    plots.curve(ax, e32m.index, avg, index=3, label="average (95% CI)", fmt="ks-",
                yerr=e32m["95% CI +-"])  # fmt: skip
    ax.set_xscale("log")
    plots.label_axes(ax, "camera period T_v (T_s)", "RMS position error (m)",
                     "E3.2 (Fig. 3-6): periodic cooperation, sigma^2 = 5 deg^2")  # fmt: skip
    plots.legend(ax)
    fig_path = plots.save(fig, ctx.figure_path("e32_periodic"))
    monotone = bool(np.all(np.diff(avg.to_numpy()) > 0))
    best = bp.summarise(e32, ["T_v"])
    above = bp.above_claim(
        CLAIM_KINDS, "BP_ours_above_bound_e32", "E3.2, every T_v and object", best
    )
    body = f"""## E3.2 Periodic cooperation (Figs. 3-5, 3-6; C8)

{int(e32m["trials"].min())} trials per camera period (the paper: 1,000), sigma^2 = 5 deg^2, 500
particles per object per model, run as batches of independent runs (one array axis per run,
:func:`fusetrack.management.camera_triggering.run_periodic_batch`, whose law equals the
single-run loop's -- tested). RMS position error (m) per object, the average over objects with
its 95 % confidence interval over trials:

{e32m.to_markdown(floatfmt=".3f")}

The average rises {"monotonically" if monotone else "not monotonically"} with T_v over the
periods run; the paper: "the error decreases as T_v approaches T_s" with "no clear optimal T_v".
The paper sweeps every T_v = 1 ... 100; we run the periods above (the cost of a trial does not
depend on T_v, so the grid is a cost choice, not a result).

The best possible beside it (:mod:`fusetrack.experiments.lee2009.bearing_bound`): the CRLB of
each object's position on the simulated model (deterministic turns at the scheduled steps, its
bearings at sigma^2 = 5 deg^2 with known association, the camera fixes of 0.1 m every T_v, the
start known as the filters are told it: the fix and the velocity to 0.02 m/s), against our RMS
over runs (root of the mean over runs of each run's mean square error; ± s.e.) and mean over runs
of the per-run RMS (the table above). The mean-RMS bound is the RMS bound / sqrt(3) (Gaussian
errors; :mod:`fusetrack.experiments.lee2009.best_possible`). The paper prints no RMS values for
Fig. 3-6, so no paper number is judged here. {bp.verdicts([above])}.

{bp.md(best)}

![E3.2]({fig_path.name})
"""
    return [claim, above], body


def run_sweep(ctx: RunContext) -> Outcome:
    """``lee2009-periodic-sweep``: E3.2 alone at the paper's 1,000 trials (Fig. 3-6)."""
    trials = ctx.n_runs(full=1000, quick=6)
    tv_sweep = [1, 10, 100] if ctx.quick else SWEEP_PERIODS
    tv_sweep = list(SweepOptions.of(ctx).periods or tv_sweep)  # --set periods=1,10,100
    n_part = 100 if ctx.quick else 500
    batches = _batch_configs("E3.2", 5.0, tv_sweep, trials, 10, n_part)
    df = ctx.monte_carlo(run_batch, batches, 1, desc="E3.2 batches")
    claims, body = _sweep_section(ctx, df, tv_sweep)
    return Outcome(df, claims, body, trials)


@dataclass(frozen=True)
class _Plan:
    """The run's sizes and configurations (E3.1/E3.2 batches, E3.4 policies, E3.5 room)."""

    n_part: int
    runs: int
    tv_grid: list[int]
    tv_sweep: list[int]
    ablations: list[str]
    n35: int
    runs35: int
    batches: list[dict[str, Any]]
    configs: list[dict[str, Any]]
    room: list[dict[str, Any]]
    readings: list[str]  # READINGS run (--quick: the default only)
    runs_variant: int  # runs of the E3.4 readings other than the default
    tv_variant: list[int]  # their periodic grid
    variant_configs: list[dict[str, Any]]


@dataclass(frozen=True)
class _Table31:
    """E3.4 (Table 3.1): RMS per policy and object, the periodic curve, triggered periods."""

    tab: pd.DataFrame
    per: pd.DataFrame
    tvs: np.ndarray
    tv_trig: float
    tv_trig_obj: dict[str, float]
    equiv: dict[str, float]


@dataclass(frozen=True)
class _Room:
    """E3.5: trigger probability per step, the events and the two comparisons of C11."""

    prob: dict[tuple[str, bool], np.ndarray]
    events: dict[str, list[int]]
    near_ratio: dict[str, tuple[float, float]]
    coop_less: dict[str, tuple[float, float]]


def run(ctx: RunContext) -> Outcome:
    """E3.1-E3.5: plan, Monte Carlo, claims C7-C11, figures, report text."""
    plan = _plan(ctx)
    parts = [
        ctx.monte_carlo(run_batch, plan.batches, 1, desc="E3.1/E3.2 batches"),
        ctx.monte_carlo(run_once, plan.configs, plan.runs),
        ctx.monte_carlo(run_once, plan.room, plan.runs35, desc="room"),
    ]
    if plan.readings != [DEFAULT_READING]:
        parts.append(
            ctx.monte_carlo(run_once, plan.variant_configs, plan.runs_variant, desc="readings")
        )
    df = pd.concat(parts, ignore_index=True)
    claims: list[Claim] = []
    obj = df[df["object"].isin(["O1", "O2", "O3"]) & df["rms"].notna()]
    c7s, e31s = _noise_claims(obj[obj.part == "E3.1"])
    claims += c7s
    e31_best_claims, e31_best = _e31_best(obj[obj.part == "E3.1"])
    claims += e31_best_claims
    c8, e32_body = _sweep_section(ctx, obj[obj.part == "E3.2"], plan.tv_sweep)
    claims += c8
    e34 = obj[obj.part == "E3.4"]
    t31s: dict[str, _Table31] = {}
    for name in plan.readings:
        grid = plan.tv_grid if name == DEFAULT_READING else plan.tv_variant
        t31_claims, t31s[name] = _table31_claims(
            e34[e34.reading == name], grid, plan.ablations, _suffix(name)
        )
        claims += t31_claims
    t31_best_claims, t31_best = _t31_best(e34)
    claims += t31_best_claims
    t31 = t31s[DEFAULT_READING]
    fired = (
        df[(df.part == "E3.4") & (df.object == "fired")]
        .groupby(["reading", "policy"])[["fired_count", "fired_gate", "fired_ellipse"]]
        .mean()
        .loc[DEFAULT_READING]
    )
    room_claims, room = _room_claims(df)
    claims += room_claims
    e31 = e31s[("spec", DEFAULT_READING)]
    figs = _figures(ctx, e31, t31, room)
    body = _report_text(plan, e31, e32_body, t31, fired, room, figs, (e31_best, t31_best))
    body += _readings_text(plan, claims, e31s, t31s) if len(plan.readings) > 1 else ""
    return Outcome(df, claims, body, plan.runs)


def _suffix(reading: str, scenario: str = "spec") -> str:
    """Claim-id suffix: none for the spec scenario and the default reading."""
    return ("" if scenario == "spec" else f"_{scenario}") + (
        "" if reading == DEFAULT_READING else f"_variant_{reading}"
    )


def _plan(ctx: RunContext) -> _Plan:
    quick = ctx.quick
    n_part = 100 if quick else 500
    runs = ctx.n_runs(full=100, quick=2)
    runs_variant = ctx.n_runs(full=40, quick=1)
    readings = [DEFAULT_READING] if quick else list(READINGS)  # --quick: keep it cheap
    variances = [0.0, 0.5, 1.5, 5.0]
    tv_grid = [1, 5, 20] if quick else [1, 2, 3, 4, 5, 6, 8, 10, 20, 50, 100]
    tv_variant = [1, 2, 4, 6, 8, 12, 20, 100]
    tv_sweep = [1, 10, 100] if quick else SWEEP_PERIODS
    ablations = ["trigger without count", "trigger without gate", "trigger without ellipse"]
    if not quick:
        ablations += ["only count", "only gate", "only ellipse"]
    # E3.1 / E3.2 as batches (chunks of trials; every chunk runs all its periods at once)
    trials32 = ctx.n_runs(full=1000, quick=4) if ctx.runs is None else ctx.runs
    batches: list[dict[str, Any]] = []
    for sc, r, v in itertools.product(VELOCITIES_31, readings, variances):
        if r == DEFAULT_READING:
            batches += _batch_configs("E3.1", v, [0], runs, 50, n_part, scenario=sc, reading=r)
        elif v in (0.0, 5.0):  # the other readings: the two ends C7 compares
            batches += _batch_configs(
                "E3.1", v, [0], runs_variant, 50, n_part, scenario=sc, reading=r
            )
    batches += _batch_configs("E3.2", 5.0, tv_sweep, trials32, 10, n_part)
    configs = [
        {"part": "E3.4", "policy": p, "n_particles": n_part, "reading": DEFAULT_READING}
        for p in ["none", "trigger", *ablations] + [f"periodic {t}" for t in tv_grid]
    ]
    variant_configs = [
        {"part": "E3.4", "policy": p, "n_particles": n_part, "reading": r}
        for r in readings
        if r != DEFAULT_READING
        for p in ["none", "trigger", *ablations[:3]] + [f"periodic {t}" for t in tv_variant]
    ]
    n35 = 50 if quick else 500
    runs35 = ctx.n_runs(full=20, quick=1) if ctx.runs is None else max(1, ctx.runs // 5)
    room = [
        {"part": "E3.5", "sensor": s, "cooperation": c, "n_particles": n35}
        for s in SENSORS_35
        for c in (True, False)
    ]
    return _Plan(
        n_part, runs, tv_grid, tv_sweep, ablations, n35, runs35, batches, configs, room,
        readings, runs_variant, tv_variant, variant_configs,
    )  # fmt: skip


def _noise_claims(e31: pd.DataFrame) -> tuple[list[Claim], dict[tuple[str, str], pd.DataFrame]]:
    """C7 (E3.1) per scenario and reading: acoustic-only RMS rises with the bearing noise,
    judged on the paired per-trial difference avg(sigma^2 = 5) - avg(sigma^2 = 0)."""
    claims, tables = [], {}
    for (sc, r), g in e31.groupby(["scenario", "reading"], sort=False):
        tab = g.groupby(["variance_deg2", "object"])["rms"].mean().unstack("object")
        tab["average"] = tab.mean(axis=1)
        per_trial = g.groupby(["variance_deg2", "trial"])["rms"].mean().unstack("variance_deg2")
        diff = paired_interval(per_trial[5.0], per_trial[0.0])
        tables[(str(sc), str(r))] = tab
        claims.append(
            CLAIM_KINDS.claim(
                "C7_rises_with_noise" + _suffix(str(r), str(sc)),
                f"acoustic-only average RMS at sigma^2 = 5 exceeds that at sigma^2 = 0 ({sc} "
                f"velocities, {r}; paired over trials: 5 - 0 [mean, 95% half-width]; O1-O3 at 5 "
                "beside the paper)",
                {"sigma2=5": PAPER_E31},
                {
                    "avg by sigma2": [round(v, 3) for v in tab["average"]],
                    "sigma2=5": [round(float(tab.loc[5.0, c]), 3) for c in ("O1", "O2", "O3")],
                    "5 - 0": interval_values(diff),
                },
                "interval of 5 - 0 above 0",
                shown_positive(diff),
            )
        )
    return claims, tables


def _e31_best(e31: pd.DataFrame) -> tuple[list[Claim], str]:
    """The best possible beside E3.1: the CRLB per scenario, reading and sigma^2 > 0 against
    ours, and Fig. 3-4's sigma^2 = 5 numbers judged on each scenario (the paper only draws its
    trajectories: each scenario is a reading)."""
    tab = bp.summarise(e31[e31["variance_deg2"] > 0], ["scenario", "reading", "variance_deg2"])
    claims = [bp.above_claim(CLAIM_KINDS, "BP_ours_above_bound_e31", "E3.1, sigma^2 > 0", tab)]
    paper = dict(zip(bp.OBJECTS, PAPER_E31, strict=True))
    for sc in VELOCITIES_31:
        at5 = tab[
            (tab.scenario == sc) & (tab.reading == DEFAULT_READING) & (tab.variance_deg2 == 5)
        ]
        claims += bp.paper_claims(
            CLAIM_KINDS, "BP_possible_e31" + _suffix(DEFAULT_READING, sc),
            "acoustic-only RMS at sigma^2 = 5 (Fig. 3-4)", paper,
            dict(zip(at5["object"], at5["mean-RMS bound"], strict=True)), f"{sc} velocities",
        )  # fmt: skip
    shown = tab[tab.reading == DEFAULT_READING].drop(columns="reading")
    text = f"""The best possible beside it (:mod:`fusetrack.experiments.lee2009.bearing_bound`): the CRLB of
each object's position on the simulated model (its deterministic turns at the scheduled steps,
one bearing per object and step with known association, the start known as the filters are told
it: the camera fix of 0.1 m and the velocity to 0.02 m/s), along each scenario's truths; no
bound at sigma^2 = 0 (exact bearings). Ours: RMS over runs (± s.e.) and mean over runs of the
per-run RMS; the mean-RMS bound (RMS bound / sqrt(3), Gaussian errors) is what a paper's mean of
per-run RMS values is judged against. Fig. 3-4's O1-O3 at sigma^2 = 5 (3.98, 9.80, 1.08 m; the
text does not say over how many runs) against each scenario's bound, a reading since the paper
only draws its trajectories: {bp.verdicts(claims)}. A paper number below a scenario's bound says
that this scenario, with a start known to 0.1 m and 0.02 m/s, cannot be the paper's (its "initial
state given" may mean a start known exactly, on which a deterministic truth has no error to
bound), not that the paper's filter is wrong.

{bp.md(shown)}"""
    return claims, text


@functools.cache
def every_step_bound_e33(alpha: float) -> tuple[float, ...]:
    """E3.4: each object's CRLB on its mean square position error over the steps it is present
    with a camera fix at every one of them: below the bound of any camera schedule."""
    truth, present = truth_e33(alpha)
    tracker = _tracker_33(1)
    ms = run_bound_ms(
        truth, schedule_alphas(schedule_e33(alpha), 1.0, T_33), 1.0, (25.0, 25.0),
        math.sqrt(3.0) * DEG, present, present, present, tracker.sigma_r,
        tracker.init_velocity_std,
    )  # fmt: skip
    return tuple(float(m) for m in ms)


def _t31_best(e34: pd.DataFrame) -> tuple[list[Claim], str]:
    """The best possible beside Table 3.1: the CRLB at every run's own camera steps against
    ours, the paper's no-cooperation row judged on the acoustic-only bound and its triggering
    row on the bound with a camera fix at every step (the paper's triggered steps are not
    known; no schedule beats every step)."""
    tab = bp.summarise(e34, ["reading", "policy"])
    claims = [bp.above_claim(CLAIM_KINDS, "BP_ours_above_bound_e34", "E3.4, every policy", tab)]
    t = tab[tab.reading == DEFAULT_READING].set_index(["policy", "object"])
    every = every_step_bound_e33(READINGS[DEFAULT_READING].alpha)
    every_mean = {o: math.sqrt(m) * bp.MEAN_FACTOR for o, m in zip(bp.OBJECTS, every, strict=True)}
    every_mean["average"] = float(np.mean(list(every_mean.values())))
    names = [*bp.OBJECTS, "average"]
    model = "the spec's O3 start and turn directions"
    claims += bp.paper_claims(
        CLAIM_KINDS, "BP_possible_t31_none", "no cooperation, RMS (Table 3.1a)",
        dict(zip(names, PAPER_T31["none"], strict=True)),
        {o: float(t.loc[("none", o), "mean-RMS bound"]) for o in names}, model,
    )  # fmt: skip
    claims += bp.paper_claims(
        CLAIM_KINDS, "BP_possible_t31_trigger",
        "triggered cooperation, RMS (Table 3.1a) against a camera fix at every step",
        dict(zip(names, PAPER_T31["trig"], strict=True)), every_mean, model,
    )  # fmt: skip
    judged = pd.DataFrame(
        {
            "paper none": PAPER_T31["none"],
            "mean-RMS bound, no cameras": [t.loc[("none", o), "mean-RMS bound"] for o in names],
            "paper triggering": PAPER_T31["trig"],
            "mean-RMS bound, camera every step": [every_mean[o] for o in names],
        },
        index=pd.Index(names, name="object"),
    ).reset_index()
    shown = tab[(tab.reading == DEFAULT_READING) & tab.policy.isin(["none", "trigger"])]
    text = f"""The best possible beside it (:mod:`fusetrack.experiments.lee2009.bearing_bound`): the CRLB of
each object's position on the simulated model over the steps it is tracked (its deterministic
turns, one bearing per object and step at 3 deg^2 with known association, the camera fixes of
0.1 m at the steps our run used them, the start known as the filters are told it: the fix and
the velocity to 0.02 m/s), against ours (RMS over runs ± s.e., mean over runs):

{bp.md(shown.drop(columns="reading"))}

The paper's numbers are means over its 100 trials of each trial's RMS, judged against the
mean-RMS bound (RMS bound / sqrt(3), Gaussian errors); its triggered camera steps are not known,
so its triggering row is judged against the bound with a camera fix at every step, which no
schedule beats. The bound takes the spec's O3 start and turn directions (the text gives
neither):

{bp.md(judged)}

{bp.verdicts(claims)}."""
    return claims, text


def _table31(e34: pd.DataFrame, tv_grid: list[int]) -> _Table31:
    """E3.4 (Table 3.1) for one reading: RMS per policy and object, the periodic curve, the
    triggered periods and the periodic T_v matching the triggering RMS (interpolated)."""
    tab = e34.groupby(["policy", "object"])["rms"].mean().unstack("object")
    tab["average"] = tab.mean(axis=1)
    upd = e34.groupby(["policy", "object"])[["tracked_steps", "camera_updates"]].sum()
    trig_upd = upd.loc["trigger"]
    tv_trig_obj = (trig_upd["tracked_steps"] / trig_upd["camera_updates"].clip(lower=1)).to_dict()
    tv_trig = float(trig_upd["tracked_steps"].sum() / max(trig_upd["camera_updates"].sum(), 1))
    per = tab.loc[[f"periodic {t}" for t in tv_grid]]
    tvs = np.array(tv_grid, float)

    def equivalent_tv(col: str) -> float:
        target = float(tab.loc["trigger", col])
        y = per[col].to_numpy()
        if target <= y[0]:
            return float(tvs[0])
        idx = np.nonzero(y >= target)[0]
        if len(idx) == 0:
            return float(tvs[-1])
        i = idx[0]
        return float(np.interp(target, [y[i - 1], y[i]], [tvs[i - 1], tvs[i]]))

    equiv = {c: equivalent_tv(c) for c in ("O1", "O2", "O3", "average")}
    return _Table31(tab, per, tvs, tv_trig, tv_trig_obj, equiv)


def _table31_claims(
    e34: pd.DataFrame, tv_grid: list[int], ablations: list[str], suffix: str = ""
) -> tuple[list[Claim], _Table31]:
    """C9, C10 (E3.4, Table 3.1) for one reading: triggering against none, periodic, and without
    each condition. Orderings are judged on paired per-run differences of the average RMS over
    the three objects (runs share their seeds across policies)."""
    t = _table31(e34, tv_grid)
    tab, tv_trig, equiv = t.tab, t.tv_trig, t.equiv
    by_run = e34.groupby(["run", "policy"])["rms"].mean().unstack("policy")
    none_gain = paired_interval(by_run["none"], by_run["trigger"])
    floor = max([tv for tv in tv_grid if tv <= tv_trig], default=None)
    at_budget = by_run[f"periodic {floor}"] if floor else np.full(len(by_run), np.nan)
    budget_gain = paired_interval(at_budget, by_run["trigger"])
    abl = {a: paired_interval(by_run[a], by_run["trigger"]) for a in ablations[:3]}
    reading = f" [{suffix.removeprefix('_variant_')}]" if suffix else ""
    claims = [
        CLAIM_KINDS.claim(
            "C9_trigger_beats_none" + suffix,
            f"triggered cooperation cuts the average RMS of no cooperation (Table 3.1a){reading}; "
            "paired over runs: none - trigger [mean, 95% half-width]",
            {"none": PAPER_T31["none"][3], "trigger": PAPER_T31["trig"][3]},
            {
                "none": round(float(tab.loc["none", "average"]), 3),
                "trigger": round(float(tab.loc["trigger", "average"]), 3),
                "none - trigger": interval_values(none_gain),
            },
            "interval of none - trigger above 0",
            shown_positive(none_gain),
        ),
        CLAIM_KINDS.claim(
            "C9_fewer_camera_uses" + suffix,
            "periodic T_v giving the triggering RMS is shorter than the mean triggered period "
            f"(triggering needs fewer camera uses; Table 3.1b){reading}",
            {"periodic-equivalent": PAPER_TV_EQUIV[3], "triggered": PAPER_TV_TRIG},
            {"periodic-equivalent": round(equiv["average"], 3), "triggered": round(tv_trig, 3)},
            "equivalent < triggered",
            equiv["average"] < tv_trig,
        ),
        CLAIM_KINDS.claim(
            "C9_cheaper_than_periodic" + suffix,
            "periodic cooperation with at least the triggered camera budget (the largest T_v run "
            "not above the mean triggered period) is less accurate than triggering"
            f"{reading}; paired over runs: periodic - trigger",
            "triggering needs fewer camera uses for the same accuracy (4.55 vs 4.21 T_s)",
            {
                "triggered T_v": round(tv_trig, 3),
                "periodic T_v": floor,
                "periodic - trigger": interval_values(budget_gain),
            },
            "interval of periodic - trigger above 0",
            shown_positive(budget_gain),
        ),
        CLAIM_KINDS.claim(
            "C10_each_condition_helps" + suffix,
            "removing any one trigger condition raises the average RMS (trigger without count / "
            f"gate / ellipse vs all){reading}; paired over runs: without - all",
            "each condition catches cases the others miss",
            {"all": round(float(tab.loc["trigger", "average"]), 3)}
            | {k: interval_values(v) for k, v in abl.items()},
            "all three intervals above 0",
            all(shown_positive(v) for v in abl.values()),
        ),
    ]
    return claims, t


def _room_claims(df: pd.DataFrame) -> tuple[list[Claim], _Room]:
    """C11 (E3.5): triggers cluster at events and persist less with cooperation."""
    claims: list[Claim] = []
    e35 = df[(df.part == "E3.5") & (df.object == "trigger_series")]
    prob: dict[tuple[str, bool], np.ndarray] = {}
    for (s, c), g in e35.groupby(["sensor", "cooperation"]):
        series = np.array([np.asarray(v, float) for v in g["fired_series"]])
        prob[(s, bool(c))] = series.mean(axis=0)
    events = {"A1": [500, 700, 1500, 1600], "A2": [1100, 1300]}
    near_ratio, coop_less = {}, {}
    for s, ev in events.items():
        near = np.zeros(T_35, bool)
        for e in ev:
            near[max(e - 20, 0) : e + 60] = True
        p = prob[(s, True)]
        near_ratio[s] = (float(p[near].mean()), float(p[~near].mean()))
        coop_less[s] = (float(prob[(s, True)].mean()), float(prob[(s, False)].mean()))
    claims.append(
        CLAIM_KINDS.claim(
            "C11_triggers_at_events",
            "with cooperation, trigger probability is higher within -0.2..+0.6 s of silence/appearance/disappearance events than elsewhere (per sensor: near, elsewhere)",
            "triggers cluster at events",
            {s: [round(a, 4), round(b, 4)] for s, (a, b) in near_ratio.items()},
            "near > elsewhere for A1 and A2",
            all(a > b for a, b in near_ratio.values()),
        )
    )
    claims.append(
        CLAIM_KINDS.claim(
            "C11_fewer_persistent",
            "mean trigger probability with cooperation below that without (per sensor: with, without)",
            "fewer persistent triggers with cooperation",
            {s: [round(a, 4), round(b, 4)] for s, (a, b) in coop_less.items()},
            "with < without for A1 and A2",
            all(a < b for a, b in coop_less.values()),
        )
    )

    return claims, _Room(prob, events, near_ratio, coop_less)


def _figures(ctx: RunContext, e31: pd.DataFrame, t31: _Table31, room: _Room) -> dict[str, Path]:
    """Figs. 3-4, 3-14, 3-16 and 3-18 ... 3-20."""
    tab, per, tvs, tv_trig_obj = t31.tab, t31.per, t31.tvs, t31.tv_trig_obj
    prob, events = room.prob, room.events
    figs = {}
    fig, ax = plots.panel(size=(6, 4))
    plots.curves(ax, e31.index, {c: e31[c] for c in ("O1", "O2", "O3", "average")})
    plots.label_axes(ax, "bearing noise variance (deg^2)", "RMS position error (m)",
                     "E3.1 (Fig. 3-4): acoustic only")  # fmt: skip
    plots.legend(ax)
    figs["e31"] = plots.save(fig, ctx.figure_path("e31_noise_sweep"))
    fig, axs = plots.panels(3, size=(14, 4))
    for ax, c in zip(axs, ("O1", "O2", "O3")):
        plots.curve(ax, tvs, per[c], index=0, label="periodic")
        tv = tv_trig_obj.get(c, float("nan"))
        plots.reference_line(ax, float(tab.loc["trigger", c]), f"triggering (T_v {tv:.2f})",
                             color="r", linestyle="-")  # fmt: skip
        plots.reference_line(ax, float(tab.loc["none", c]), "none", linestyle="--")
        ax.set_xscale("log")
        plots.label_axes(ax, "T_v (T_s)", "RMS position error (m)", f"Fig. 3-14: {c}")
        plots.legend(ax, fontsize=7)
    figs["e34"] = plots.save(fig, ctx.figure_path("fig3_14"))
    fig, axs = plots.figure(2, 2, size=(13, 6), sharex=True)
    t35 = np.arange(T_35)
    for i, s in enumerate(SENSORS_35):
        for j, coop in enumerate((True, False)):
            ax = axs[j, i]
            plots.curve(ax, t35, prob[(s, coop)], index=0, label="P(trigger)", lw=0.8, marker="")
            for k, e in enumerate(events[s]):
                plots.reference_line(ax, e, "event" if k == 0 else "", axis="x", color="r", lw=0.6)
            plots.label_axes(ax, "step (T_s = 0.01 s)" if j == 1 else "", "P(trigger)",
                             f"{s}, {'with' if coop else 'without'} cooperation")  # fmt: skip
    plots.legend(axs[0, 0], fontsize=7)
    figs["e35"] = plots.save(fig, ctx.figure_path("fig3_18_20_trigger_probability"))
    tr35 = truth_e35()
    fig, ax = plots.panel(size=(8, 4.8))
    plots.draw_paths(ax, [tr35[:, o] for o in range(3)], labels=[f"O{o + 1}" for o in range(3)])
    acoustic = [(n, p) for n, p in SENSORS_35.items() if n.startswith("A")]
    cameras = [(n, p) for n, p in {**SENSORS_35, **CAMERAS_35}.items() if not n.startswith("A")]
    plots.draw_sensors(ax, acoustic, label="acoustic array")
    plots.draw_sensors(ax, cameras, marker="s", label="camera")
    ax.set_xlim(0, ROOM[0])
    ax.set_ylim(0, ROOM[1])
    ax.set_aspect("equal")
    plots.label_axes(ax, title="Figs. 3-15/3-16: the room, trajectories, sensors")
    plots.legend(ax, fontsize=7)
    figs["room"] = plots.save(fig, ctx.figure_path("fig3_16_room"))

    return figs
    return figs


def _report_text(
    plan: _Plan,
    e31: pd.DataFrame,
    e32_body: str,
    t31_: _Table31,
    fired: pd.DataFrame,
    room: _Room,
    figs: Mapping[str, Path],
    best: tuple[str, str],
) -> str:
    """The report body; ``best``: the best-possible sections beside E3.1 and Table 3.1."""
    n_part, runs, n35, runs35 = plan.n_part, plan.runs, plan.n35, plan.runs35
    tab, tv_trig, tv_trig_obj, equiv = t31_.tab, t31_.tv_trig, t31_.tv_trig_obj, t31_.equiv
    near_ratio, coop_less = room.near_ratio, room.coop_less
    t31 = [
        "| | paper none | ours none | paper triggering | ours triggering | paper periodic-equivalent T_v | ours | ours triggered T_v |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for i, c in enumerate(("O1", "O2", "O3", "average")):
        trig_tv = tv_trig if c == "average" else tv_trig_obj.get(c, float("nan"))
        t31.append(
            f"| {c} | {PAPER_T31['none'][i]} | {tab.loc['none', c]:.3f} | {PAPER_T31['trig'][i]} | {tab.loc['trigger', c]:.3f} | {PAPER_TV_EQUIV[i]} | {equiv[c]:.2f} | {trig_tv:.2f} |"
        )
    return f"""
Filters: one multi-model particle filter per object (CV, CT, ACT with alpha = {ALPHA_33} m/s^2 in
Sec. 3.3, 0.3 m/s^2 in the room), {n_part} particles per model per object ({n35} in the room),
{runs} runs ({runs35} in the room); consistent JPDA estimator (the printed chain (3.7)-(3.11) is not convex). Bearings
closer than 2 deg merge. Camera fixes: truth + N(0, 0.1^2) m (0.05 m in the room), applied at once.
Filters started at step 0 (or, without cameras, when an object appears) know its position to
the fix noise and its velocity to 0.02 m/s (the text: "initial state given"); filters started by
a camera know only the position.

## E3.1 Acoustic only (Fig. 3-4; C7)

{e31.to_markdown(floatfmt=".3f")}

Paper at sigma^2 = 5: O1 3.98, O2 9.80, O3 1.08 m. The trajectories are only drawn in the paper's
figure; ours are the spec's choice, so only the trend is comparable. Bearings-only tracking from
one static sensor cannot observe range; the error grows with time as the range drifts, and a
filter that weights every particle against every unlabelled bearing can also slide onto another
object's bearing. At sigma^2 = 0 the filter uses sigma^2 = 0.1 deg^2 (a zero-width likelihood is
degenerate).

{best[0]}

![E3.1]({figs["e31"].name})

{e32_body}

## E3.4 Triggering against periodic and none (Table 3.1, Fig. 3-14; C9, C10)

{chr(10).join(t31)}

{best[1]}

All policies (average RMS, m):

{tab.to_markdown(floatfmt=".3f")}

Steps at which each condition fired (mean per run):

{fired.to_markdown(floatfmt=".1f")}

![Fig 3-14]({figs["e34"].name})

Policies without the count trigger cannot find objects that enter; for them (and for "none") an
oracle starts a filter when an object appears, so the ablations compare the same objects.

Differences: the absolute RMS values depend on trajectories and turn directions the text does not
give (the spec imposes the stated visibility schedule). The comparison the paper draws -- the
periodic period that matches the triggering accuracy against the mean triggered period -- is
computed from the measured periodic curve by interpolation.

## E3.5 Indoor room (Figs. 3-15 ... 3-21; C11)

Two sensors A1 {SENSORS_35["A1"]}, A2 {SENSORS_35["A2"]}, 100 samples/s, 19 s, variance 3 deg^2,
visibility and silence imposed as the text describes them (corrected typos, spec Sec. 5.5).
Probability (fraction of runs) that any trigger fires, per step; red lines mark the events
(A1: O1 silent 5.0-7.0 s, O1 leaves at 15 s, O2 appears at 15 s, O3 at 16 s; A2: O1 appears at
11 s, O3 at 13 s). Mean probability near events vs elsewhere: { ({s: [round(a, 4), round(b, 4)] for s, (a, b) in near_ratio.items()}) };
with vs without cooperation: { ({s: [round(a, 4), round(b, 4)] for s, (a, b) in coop_less.items()}) }.

![trigger probability]({figs["e35"].name})

![room]({figs["room"].name})
"""


def _readings_text(
    plan: _Plan,
    claims: Sequence[Claim],
    e31s: Mapping[tuple[str, str], pd.DataFrame],
    t31s: Mapping[str, _Table31],
) -> str:
    """The report section on what the text leaves open: velocities, alpha, estimator."""
    holds = {c.id: "yes" if c.holds else "**no**" for c in claims}
    c7 = pd.DataFrame(
        {
            r: {sc: holds["C7_rises_with_noise" + _suffix(r, sc)] for sc in VELOCITIES_31}
            for r in READINGS
        }
    )
    avg = pd.DataFrame({f"{sc}, {r}": tab["average"] for (sc, r), tab in e31s.items()}).T
    ids = ["C9_trigger_beats_none", "C9_fewer_camera_uses", "C9_cheaper_than_periodic"]
    ids += ["C10_each_condition_helps"]
    verdicts = pd.DataFrame({r: {i: holds[i + _suffix(r)] for i in ids} for r in READINGS})
    nums = pd.DataFrame(
        {
            r: {
                "none": t.tab.loc["none", "average"],
                "trigger": t.tab.loc["trigger", "average"],
                "triggered T_v": t.tv_trig,
                "periodic-equivalent T_v": t.equiv["average"],
                **{a: t.tab.loc[a, "average"] for a in plan.ablations[:3]},
            }
            for r, t in t31s.items()
        }
    )
    return f"""
## What the text leaves open: velocities, alpha, estimator (C7, C9, C10 per reading)

Readings: **alpha=1** (the default: turns with alpha = 1 m/s^2, as Eq. 3.13's text; consistent
estimator), **alpha=0.01** (the bullet's "manoeuvre rotation acceleration 0.01 m/s^2" for the truth
and the filter's CT/ACT models), **printed** (alpha = 1, the printed estimator chain
(3.7)-(3.11), which shrinks the estimate towards the origin by up to 1/J^2 = 1/9 when the models
share the weight). E3.1 velocities (not in the text): **spec** {VELOCITIES_31["spec"]} (O2 and O3
within 2 deg for 70 of 200 steps, O1 and O2 for 18: association, not noise, dominates) and
**apart** {VELOCITIES_31["apart"]} (bearings at least 10 deg apart throughout, under both alphas).
Which is the paper's: the text states alpha = 1 m/s^2 with Eq. 3.13 and 0.01 m/s^2 in the bullet
(both are its words); the estimator it prints is the chain (3.7)-(3.11), but its Fig. 3-4 errors
(O3 1.08 m at sigma^2 = 5) are out of reach of a chain that pulls every estimate towards the
sensor, so the consistent estimator is the reading its numbers imply; its velocities are only
drawn, and its noise trend needs objects whose bearings do not merge for long ("apart").
The default reading runs {plan.runs} runs; the others {plan.runs_variant} runs with periodic
T_v = {plan.tv_variant}. Orderings are judged on 95 % intervals of paired per-run differences.

C7 (acoustic-only RMS rises with the noise), verdict per velocities (rows) and reading:

{c7.to_markdown()}

Average RMS (m) by sigma^2 (deg^2):

{avg.to_markdown(floatfmt=".3f")}

C9, C10 (E3.4) per reading:

{verdicts.to_markdown()}

{nums.to_markdown(floatfmt=".3f")}

"Triggering is cheaper than periodic camera use" (the chapter's contribution) is
C9_cheaper_than_periodic: periodic cooperation with at least the triggered camera budget (the
largest T_v run not above the mean triggered period) is less accurate than triggering, paired over
runs. C9_fewer_camera_uses is the paper's own comparison (Table 3.1b) on mean curves; it clamps
at T_v = 1, so it "holds" vacuously when triggering asks the cameras at every step (printed).
"""
