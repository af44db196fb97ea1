"""Beyond the paper (issue 5): the filters a practitioner would compare today, at equal time.

For one experiment's scenario (:class:`Scenario`: motion, sensors, prior, measurements, truth)
:func:`run_comparators` runs

* **UPF**: the unscented-proposal particle filter (:class:`~fusetrack.filters.unscented_proposal.UnscentedProposal`);
* **IMM-EKF**: one EKF per motion model of ``Scenario.imm_models`` mixed by the IMM; with no
  models given it is the one-model IMM on ``Scenario.motion``, which *is* the EKF (the mixing step
  is the identity), so the row is labelled "IMM-EKF" but computes the EKF;
* **bootstrap equal time**: the transition-prior particle filter with as many particles as fit in
  the time of the method it is compared with (the paper's proposed filter, "reference").

**Equal time, the rule** (:func:`calibrate_particles`): before the Monte Carlo runs, time the
reference filter on one scenario (the fastest of ``repeats`` runs, :func:`pilot_seconds`), time
the comparator at two pilot particle counts ``n1 < n2`` the same way, fit the affine cost
``t(N) = a + b N`` through the two points and solve ``t(N) = target`` for ``N``, rounded to a
multiple of ``step`` and clipped to ``[n_min, n_max]``. (A fixed per-step overhead ``a`` is why a
proportional rule ``N = n1 target / t(n1)`` is wrong at small N.) The UPF is calibrated the same
way ("UPF equal time") when asked.

:func:`beyond_table` turns per-run errors and seconds into the "who wins" table
(the winner at equal time is the best method among those that took at most ``slack`` times the
reference's seconds), :func:`error_vs_seconds_figure` draws error against seconds (one panel per
configuration), :func:`beyond_section` writes the report's "Beyond the paper" section and
:func:`beyond_summary` the entries for ``summary.json`` (not claims).
"""

from __future__ import annotations

import time
import zlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, NamedTuple

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from ...core import Gaussian, MotionModel, SensorModel
from ...filters import InteractingMultipleModel, ProposalParticleFilter, UnscentedProposal
from .common import Array, timed_gaussian, timed_sis

COMPARATORS = ("UPF", "IMM-EKF", "bootstrap equal time")
Better = Literal["lower", "higher"]


@dataclass(frozen=True)
class Scenario:
    """What the comparators need from one Monte Carlo run of an experiment.

    ``zs`` is one sensor-aligned sequence per step (entries ``None`` or NaN are skipped);
    ``truth`` ``(T, d)``. ``imm_models``/``imm_transition``: the IMM's models and regime matrix
    (empty: the one-model IMM on ``motion``, i.e. the EKF).
    """

    motion: MotionModel
    sensors: Sequence[SensorModel]
    prior: Gaussian
    zs: Sequence[Sequence[Array | None]]
    dt: float
    truth: Array
    imm_models: Sequence[MotionModel] = ()
    imm_transition: ArrayLike | None = None


class Timed(NamedTuple):
    """A filter's estimates ``(T, d)`` and its wall seconds for the whole run."""

    estimates: Array
    seconds: float


def imm_ekf(scn: Scenario) -> InteractingMultipleModel:
    """The IMM-EKF of ``scn`` (one model and transition ``[[1]]``: exactly the EKF)."""
    if scn.imm_models and scn.imm_transition is not None:
        return InteractingMultipleModel(list(scn.imm_models), scn.imm_transition, scn.sensors)
    return InteractingMultipleModel([scn.motion], [[1.0]], scn.sensors)


def particle_filter(scn: Scenario, method: str, n: int) -> ProposalParticleFilter:
    """``"UPF..."`` -> unscented proposal, ``"bootstrap..."`` -> transition prior, ``n`` particles."""
    if method.startswith("UPF"):
        return ProposalParticleFilter(scn.motion, scn.sensors, UnscentedProposal(), n_particles=n)
    if method.startswith("bootstrap"):
        return ProposalParticleFilter(scn.motion, scn.sensors, n_particles=n)
    raise ValueError(f"no particle filter for comparator {method!r}")


def run_comparators(
    scn: Scenario,
    seed: int,
    n_particles: Mapping[str, int],
    methods: Sequence[str] = COMPARATORS,
) -> dict[str, Timed]:
    """Run each of ``methods`` on ``scn``: ``{method: Timed}``.

    Particle filters take their count from ``n_particles[method]`` and the random stream
    ``default_rng([seed, crc32(method)])``, so adding or reordering comparators does not change
    another's numbers; non-finite estimates are kept (the caller scores them).
    """
    out: dict[str, Timed] = {}
    ids = [s.sensor_id for s in scn.sensors]
    for m in methods:
        if m == "IMM-EKF":
            est, secs = timed_gaussian(imm_ekf(scn), scn.prior, scn.zs, ids, scn.dt)
        else:
            filt = particle_filter(scn, m, int(n_particles[m]))
            est, secs, _ = timed_sis(
                filt,
                scn.prior,
                scn.zs,
                scn.dt,
                np.random.default_rng([seed, zlib.crc32(m.encode())]),
            )
        out[m] = Timed(np.asarray(est, float), float(secs))
    return out


# ----------------------------------------------------------------------------- equal time


def pilot_seconds(
    fn: Callable[[], object], repeats: int = 3, clock: Callable[[], float] = time.perf_counter
) -> float:
    """The fastest of ``repeats`` timed calls of ``fn`` (the least disturbed by other load)."""
    best = np.inf
    for _ in range(max(1, repeats)):
        t0 = clock()
        fn()
        best = min(best, clock() - t0)
    return float(best)


def calibrate_particles(
    run: Callable[[int], object],
    target_seconds: float,
    *,
    pilot: tuple[int, int] = (200, 2000),
    repeats: int = 3,
    step: int = 50,
    n_min: int = 50,
    n_max: int = 200_000,
    clock: Callable[[], float] = time.perf_counter,
) -> int:
    """Particles ``N`` with ``t(N) = target_seconds`` for the affine cost ``t(N) = a + b N``
    through the pilot timings ``(n1, t1)``, ``(n2, t2)`` (each the fastest of ``repeats`` calls of
    ``run(n)``); rounded to a multiple of ``step``, clipped to ``[n_min, n_max]``.

    If the pilot shows no growth (``t2 <= t1``: noise), the proportional rule
    ``N = n2 target / t2`` is used instead.
    """
    n1, n2 = pilot
    t1 = pilot_seconds(lambda: run(n1), repeats, clock)
    t2 = pilot_seconds(lambda: run(n2), repeats, clock)
    if t2 > t1:
        slope = (t2 - t1) / (n2 - n1)
        n = n1 + (target_seconds - t1) / slope
    else:
        n = n2 * target_seconds / max(t2, 1e-12)
    n = round(n / step) * step
    return int(min(max(n, n_min), n_max))


def equal_time_particles(
    scn: Scenario,
    reference: Callable[[], object],
    methods: Sequence[str] = ("bootstrap equal time",),
    *,
    repeats: int = 3,
    clock: Callable[[], float] = time.perf_counter,
) -> tuple[dict[str, int], float]:
    """``({method: N}, target seconds)``: each particle comparator in ``methods`` calibrated by
    :func:`calibrate_particles` to the pilot time of ``reference()`` on the same scenario.
    UPF pilots use 20 and 200 particles (a UKF per particle), the bootstrap 200 and 2000."""
    target = pilot_seconds(reference, repeats, clock)
    out = {}
    for k, m in enumerate(methods):

        def run(n: int, m: str = m, k: int = k) -> object:
            f = particle_filter(scn, m, n)
            return timed_sis(f, scn.prior, scn.zs, scn.dt, np.random.default_rng([k, n]))

        pilot = (20, 200) if m.startswith("UPF") else (200, 2000)
        out[m] = calibrate_particles(
            run, target, pilot=pilot, repeats=repeats, clock=clock, step=10 if pilot[0] < 50 else 50
        )
    return out, target


# ----------------------------------------------------------------------------- tables, figure


def beyond_table(
    per_run: pd.DataFrame,
    reference: str | Mapping[Any, str],
    *,
    by: Sequence[str] = (),
    error: str = "error",
    better: Better = "lower",
    slack: float = 1.5,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``(table, winners)`` from one row per (configuration ``by``, method, run) with columns
    ``method``, ``error`` (the experiment's score per run) and ``seconds``.

    ``table`` (index ``(*by, method)``): mean and median score, runs, seconds per run (the median
    over runs: robust to a first run's compile time and to load spikes) and seconds relative to
    ``reference``. ``winners`` (one row per configuration): the best method at equal
    time (seconds <= ``slack`` x the reference's), the best overall, and their scores.
    ``reference`` may differ per configuration: a mapping from the configuration's key (the
    value of ``by`` when it has one column, else the tuple) to the method.
    """
    keys = [*by, "method"]
    g = per_run.groupby(keys, sort=False)
    table = pd.DataFrame(
        {
            "mean": g[error].mean(),
            "median": g[error].median(),
            "runs": g[error].count(),
            "seconds/run": g["seconds"].median(),
        }
    )
    groups = table.groupby(level=list(by), sort=False) if by else [((), table)]
    rel, rows = [], []
    for key, full in groups:
        t = full.droplevel(list(by)) if by else full  # index: method
        key_t = key if isinstance(key, tuple) else (key,)
        ref = (
            reference
            if isinstance(reference, str)
            else reference[key_t[0] if len(key_t) == 1 else key_t]
        )
        r = t["seconds/run"] / float(t.loc[ref, "seconds/run"])
        rel.append(full["seconds/run"] / float(t.loc[ref, "seconds/run"]))
        ok = t.loc[r <= slack, "mean"]
        eq = ok.idxmin() if better == "lower" else ok.idxmax()
        best = t["mean"].idxmin() if better == "lower" else t["mean"].idxmax()
        rows.append(
            {
                **dict(zip(by, key_t)),
                "winner at equal time": eq,
                "score": float(t.loc[eq, "mean"]),
                "winner overall": best,
                "score overall": float(t.loc[best, "mean"]),
                **({} if isinstance(reference, str) else {"reference": ref}),
                f"{reference if isinstance(reference, str) else 'reference'} score": float(
                    t.loc[ref, "mean"]
                ),
            }
        )
    table["time / reference"] = pd.concat(rel)
    winners = pd.DataFrame(rows)
    winners = winners.set_index(list(by)) if by else winners.set_axis(["all"])
    return table, winners


def error_vs_seconds_figure(
    path: Path,
    table: pd.DataFrame,
    *,
    ylabel: str,
    title: str = "",
    families: Mapping[str, Sequence[str]] | None = None,
    logy: bool = True,
) -> Path:
    """Mean score against seconds per run (log x), one panel per configuration of ``table``'s
    index levels before ``method``; methods listed in a ``families`` entry are joined by a line
    (e.g. a bootstrap at several particle counts)."""
    from ...evaluation import plots

    by = [n for n in table.index.names if n != "method"]
    groups = list(table.groupby(level=by, sort=False)) if by else [((), table)]
    ncols = min(4, len(groups))
    nrows = -(-len(groups) // ncols)
    fig, axes = plots.figure(nrows, ncols, size=(4.2 * ncols + 1.8, 3.6 * nrows))
    plots.hide_unused(axes, len(groups))
    for ax, (key, t) in zip(axes.flat, groups):
        t = t.droplevel(by) if by else t
        for i, (m, row) in enumerate(t.iterrows()):
            ax.plot(row["seconds/run"], row["mean"], "osD^v<>ph*X"[i % 11], ms=6, label=str(m))
        for k, members in enumerate((families or {}).values()):
            pts = t.loc[[m for m in members if m in t.index]].sort_values("seconds/run")
            label = "same method, other sizes" if k == 0 else None
            ax.plot(pts["seconds/run"], pts["mean"], "k:", lw=1, label=label)
        plots.log_axis(ax, "x")
        if logy and bool((t["mean"] > 0).all()):
            plots.log_axis(ax, "y")
        plots.label_axes(ax, "seconds per run (s)", ylabel)
        ax.set_title(", ".join(f"{n}={v}" for n, v in zip(by, np.atleast_1d(key))) or title)
        ax.grid(alpha=0.3, which="both")
    plots.legend(axes[0][ncols - 1], fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    if title and by:
        fig.suptitle(title)
    return plots.save(fig, path)


def beyond_section(
    table: pd.DataFrame,
    winners: pd.DataFrame,
    *,
    reference: str | Mapping[Any, str],
    figure: str | None,
    calibration: str,
    notes: Sequence[str] = (),
    floatfmt: str = ".4g",
) -> str:
    """The report's "Beyond the paper" markdown section."""
    lines = [
        "## Beyond the paper: comparators at equal computing time",
        "",
        "Not paper claims. Reference (the paper's method the time is matched to): "
        + (
            f"**{reference}**. "
            if isinstance(reference, str)
            else "; ".join(f"{k}: **{v}**" for k, v in reference.items()) + ". "
        )
        + calibration,
        "",
        "Who wins (best mean score among the methods that took at most 1.5x the reference's "
        "time; and over all methods):",
        "",
        winners.to_markdown(floatfmt=floatfmt),
        "",
        table.to_markdown(floatfmt=floatfmt),
        "",
    ]
    if figure:
        lines += [f"![error against seconds]({figure})", ""]
    lines += [f"* {n}" for n in notes]
    return "\n".join(lines) + "\n"


def beyond_summary(table: pd.DataFrame, winners: pd.DataFrame, **info: Any) -> dict[str, Any]:
    """``summary.json``'s ``beyond_the_paper`` entry: winners and per-method score and time."""

    def key(k: Any) -> str:
        return " | ".join(map(str, k)) if isinstance(k, tuple) else str(k)

    return {
        **info,
        "winners": {key(k): {c: v for c, v in r.items()} for k, r in winners.iterrows()},
        "methods": {
            key(k): {"mean": float(r["mean"]), "seconds_per_run": float(r["seconds/run"])}
            for k, r in table.iterrows()
        },
    }


@dataclass
class Comparison:
    """Everything one experiment's "Beyond the paper" section needs, built by :func:`compare`."""

    table: pd.DataFrame
    winners: pd.DataFrame
    section: str
    summary: dict[str, Any] = field(default_factory=dict)


def compare(
    per_run: pd.DataFrame,
    reference: str | Mapping[Any, str],
    figure_path: Path | None,
    *,
    by: Sequence[str] = (),
    error: str = "error",
    better: Better = "lower",
    ylabel: str = "RMSE per run (mean)",
    calibration: str = "",
    notes: Sequence[str] = (),
    families: Mapping[str, Sequence[str]] | None = None,
    methods: Sequence[str] | None = None,
    **info: Any,
) -> Comparison:
    """:func:`beyond_table` + :func:`error_vs_seconds_figure` + :func:`beyond_section` +
    :func:`beyond_summary` in one call; ``methods`` (default all) selects the rows compared
    (e.g. leave out ablations)."""
    if methods is not None:
        per_run = per_run[per_run["method"].isin(list(methods))]
    table, winners = beyond_table(per_run, reference, by=by, error=error, better=better)
    fig = None
    if figure_path is not None:
        fig = error_vs_seconds_figure(
            figure_path,
            table,
            ylabel=ylabel,
            title="error against computing time"
            if better == "lower"
            else "score against computing time",
            families=families,
            logy=better == "lower",
        ).name
    section = beyond_section(
        table, winners, reference=reference, figure=fig, calibration=calibration, notes=notes
    )
    return Comparison(
        table, winners, section, beyond_summary(table, winners, reference=reference, **info)
    )


def per_run_scores(
    rows: pd.DataFrame, by: Sequence[str], sq_error: str, seconds: str = "seconds"
) -> pd.DataFrame:
    """Per-step rows -> one row per (``by``, method, run): ``error`` = RMSE over the run's steps
    (``sqrt(mean(sq_error))``) and its ``seconds``, the input of :func:`beyond_table`."""
    g = rows.groupby([*by, "method", "run"], sort=False)
    out = pd.DataFrame({"error": g[sq_error].mean().pow(0.5), "seconds": g[seconds].first()})
    return out.reset_index()


def calibration_note(
    n_particles: Mapping[Any, Mapping[str, int]], target_seconds: Mapping[Any, float]
) -> str:
    """One sentence per configuration: the calibrated particle counts and the target time."""
    parts = [
        f"{key}: target {target_seconds[key]:.3g} s -> "
        + ", ".join(f"{m} N = {n}" for m, n in ns.items())
        for key, ns in n_particles.items()
    ]
    return (
        "Equal time: before the runs the reference was timed on run 0's scenario (fastest of a few "
        "repeats), each particle comparator at two pilot particle counts, and N solved from the "
        "affine cost t(N) = a + bN through the two pilots (rounded). "
        + "; ".join(parts)
        + ". The IMM-EKF has no N to tune (it is far cheaper). Seconds per run below are the "
        "timings inside the Monte Carlo runs (two worker processes on a shared machine), so the "
        "'time / reference' column shows how well the pilot's equal time held (median seconds "
        "over runs)."
    )


def sis_reference(
    scn: Scenario, make: Callable[[], ProposalParticleFilter]
) -> Callable[[], object]:
    """A reference for :func:`equal_time_particles`: a fresh ``make()`` filter run over ``scn``."""

    def run() -> object:
        return timed_sis(make(), scn.prior, scn.zs, scn.dt, np.random.default_rng(0))

    return run


UPF_NOTE = (
    "UPF: fusetrack's shared-covariance unscented proposal (filters/unscented_proposal.py: one "
    "UKF step per particle from N(x_(t-1)^i, P), P the particle set's covariance). Its proposal "
    "is wider than the transition density, so the paired weight p(x | x_(t-1)^i) / q(x) "
    "degenerates and it needs many particles to approach the Kalman filter on a linear-Gaussian "
    "model. Its rows measure this UPF, not the best possible one."
)
