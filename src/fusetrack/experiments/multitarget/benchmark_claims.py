"""The claims of ``multitarget-benchmark``: hypotheses stated before the run, each of which can
fail. Kinds as in ``multitarget-bearings`` (:mod:`.claims`): ``beyond`` (a comparison of
trackers where theory says who should win; no paper prints these numbers) or ``diagnostic`` (a
check of the simulation or of the set-up). Comparisons of two trackers use the *paired*
difference per run (both ran on the same reports) and its standard error over runs."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from ...evaluation import Claim
from .claims import claim, claim_kinds

if TYPE_CHECKING:
    from .benchmark import Options

__all__ = ["claim_kinds", "make_claims", "mean_se", "paired_difference", "summary_table"]

METRICS = ("gospa", "localisation", "missed", "false", "ospa2", "n_tracks", "count_bias")
MOT_METRICS = ("mota", "motp", "id_switches", "fragmentations")


def values(df: pd.DataFrame, scenario: str, tracker: str, metric: str) -> np.ndarray:
    """One metric per run (ordered by run) of one tracker in one scenario."""
    sel = df[(df.scenario == scenario) & (df.tracker == tracker)].sort_values("run")
    return np.asarray(sel[metric].astype(float).to_numpy())


def mean_se(v: np.ndarray) -> tuple[float, float]:
    """Mean and standard error of the mean (0 for a single value)."""
    se = float(v.std(ddof=1) / np.sqrt(v.size)) if v.size > 1 else 0.0
    return float(v.mean()), se


def paired_difference(
    df: pd.DataFrame, scenario: str, a: str, b: str, metric: str
) -> tuple[float, float]:
    """Mean and SE over runs of ``metric(a) - metric(b)`` (same runs, same reports)."""
    return mean_se(values(df, scenario, a, metric) - values(df, scenario, b, metric))


def summary_table(df: pd.DataFrame, metrics: tuple[str, ...] = METRICS) -> pd.DataFrame:
    """``mean ± SE`` over runs of ``metrics``, one row per (scenario, tracker)."""
    rows = []
    for (scenario, tracker), _ in df.groupby(["scenario", "tracker"], sort=False):
        row: dict[str, Any] = {"scenario": scenario, "tracker": tracker}
        for m in metrics:
            mu, se = mean_se(values(df, str(scenario), str(tracker), m))
            row[m] = f"{mu:.2f} ± {se:.2f}"
        rows.append(row)
    return pd.DataFrame(rows).set_index(["scenario", "tracker"])


def _at_most(d: tuple[float, float], k: float) -> bool:
    return d[0] <= k * d[1]


def _comparison_claims(df: pd.DataFrame, k: float) -> list[Claim]:
    """JPDA against GNN in dense clutter, MHT against JPDA at the crossing."""
    jg = paired_difference(df, "dense", "JPDA", "GNN", "gospa")
    mj = paired_difference(df, "crossing", "MHT", "JPDA", "gospa")
    mj_id = paired_difference(df, "crossing", "MHT", "JPDA", "id_switches")
    pp = paired_difference(df, "dense", "PMB", "GM-PHD", "gospa")
    tol = f"{k:g} SE of the paired difference"
    return [
        claim(
            "beyond",
            "pmb_not_worse_than_phd_dense",
            "in dense clutter the PMB filter's GOSPA is at most the GM-PHD's: mean paired "
            "difference PMB - GM-PHD <= k SE (a Bernoulli per track keeps each target's "
            "existence and identity; the PHD's one intensity spreads them)",
            "PMB - GM-PHD <= 0",
            {"mean": pp[0], "se": pp[1]},
            tol,
            _at_most(pp, k),
        ),
        claim(
            "beyond",
            "jpda_not_worse_than_gnn_dense",
            "in dense clutter JPDA's GOSPA is at most GNN's: mean paired difference JPDA - GNN "
            "<= k SE (soft association does not commit to a clutter report)",
            "JPDA - GNN <= 0",
            {"mean": jg[0], "se": jg[1]},
            tol,
            _at_most(jg, k),
        ),
        claim(
            "beyond",
            "mht_not_worse_than_jpda_crossing",
            "at the crossing MHT's GOSPA is at most JPDA's: mean paired difference MHT - JPDA "
            "<= k SE (deferred decisions, no coalescence of the two tracks)",
            "MHT - JPDA <= 0",
            {"mean": mj[0], "se": mj[1]},
            tol,
            _at_most(mj, k),
        ),
        claim(
            "beyond",
            "mht_no_more_id_switches_than_jpda_crossing",
            "at the crossing MHT switches identities (CLEAR MOT) no more often than JPDA: mean "
            "paired difference MHT - JPDA <= k SE",
            "MHT - JPDA <= 0",
            {"mean": mj_id[0], "se": mj_id[1]},
            tol,
            _at_most(mj_id, k),
        ),
    ]


def _cardinality_claims(df: pd.DataFrame, k: float, settle: int) -> list[Claim]:
    """The PHD's intensity mass is an unbiased estimate of the number of targets."""
    bias = {s: mean_se(values(df, s, "GM-PHD", "count_bias")) for s in ("sparse", "dense")}
    return [
        claim(
            "beyond",
            "phd_cardinality_unbiased",
            f"the GM-PHD's expected number of targets (its intensity's mass) minus the true "
            f"number, averaged over the scans after the first {settle}, is within k SE of 0 over "
            "runs, in sparse and in dense clutter (the PHD is the first moment of the "
            "multi-target posterior; births, survival, P_D and clutter are the filter's own model)",
            "0",
            {s: {"mean": b[0], "se": b[1]} for s, b in bias.items()},
            f"|mean| <= {k:g} SE",
            all(abs(b[0]) <= k * b[1] for b in bias.values()),
        )
    ]


def _empty_gospa(df: pd.DataFrame, scenario: str, c: float) -> float:
    """GOSPA (p = 2, alpha = 2) of reporting no target at all, over the runs' true counts."""
    counts = df[(df.scenario == scenario) & (df.tracker == "GNN")]["true_count_t"]
    n = np.concatenate([np.asarray(x, float) for x in counts])
    return float(np.sqrt(np.mean(c**2 / 2 * n)))


def _simulation_statistics(
    df: pd.DataFrame, opts: Options, k: float
) -> tuple[dict[str, float], dict[str, float], bool]:
    """Expected and simulated births, clutter per sensor per scan and detected fraction, and
    whether each is within ``k`` standard deviations of its Poisson / binomial model. The sparse
    and dense runs share their worlds (common random numbers: the same seed draws the targets
    first), so births and detections are counted on the sparse runs only."""
    expected: dict[str, float] = {}
    ours: dict[str, float] = {}
    ok = True
    for scenario, clutter in (("sparse", opts.sparse_clutter), ("dense", opts.dense_clutter)):
        one = df[(df.tracker == "GNN") & (df.scenario == scenario)]
        scans = np.array([len(x) for x in one["true_count_t"]], dtype=float)
        total, mean = float((one["clutter_per_scan"] * 2 * scans).sum()), clutter * 2 * scans.sum()
        expected[f"clutter {scenario}"] = clutter
        ours[f"clutter {scenario}"] = total / (2 * scans.sum())
        ok &= abs(total - mean) <= k * np.sqrt(max(mean, 1e-12))
        if scenario != "sparse":
            continue
        births, mean_births = float(one["births"].sum()), opts.birth_rate * float(np.sum(scans - 1))
        expected["births"], ours["births"] = mean_births, births
        ok &= abs(births - mean_births) <= k * np.sqrt(mean_births)
        present = 2.0 * float(sum(np.sum(x) for x in one["true_count_t"]))
        detected = float((one["detected_fraction"] * 2 * one["true_count_t"].map(np.sum)).sum())
        expected["P_D"], ours["P_D"] = opts.p_detect, detected / present
        sd = float(np.sqrt(opts.p_detect * (1 - opts.p_detect) / present))
        ok &= abs(detected / present - opts.p_detect) <= k * sd
    return expected, ours, bool(ok)


def _diagnostic_claims(df: pd.DataFrame, opts: Options, k: float) -> list[Claim]:
    """The simulation draws what it says; every tracker does better than reporting nothing."""
    expected, ours, stats_ok = _simulation_statistics(df, opts, k)
    ours = {key: float(v) for key, v in ours.items()}  # plain floats in summary.json
    empty = {s: _empty_gospa(df, s, opts.gospa_c) for s in ("sparse", "dense", "crossing")}
    worst = {
        s: max(float(values(df, s, t, "gospa").mean()) for t in df.tracker.unique()) for s in empty
    }
    return [
        claim(
            "diagnostic",
            "scenario_statistics",
            "the simulation draws what it should: clutter reports per sensor per scan (sparse "
            "and dense runs) vs their Poisson mean, births (sparse runs) vs birth_rate x scans, "
            "detected fraction (sparse runs) vs P_D, each within k of its standard deviation",
            expected,
            ours,
            f"{k:g} sd (Poisson / binomial)",
            stats_ok,
        ),
        claim(
            "diagnostic",
            "every_tracker_beats_no_tracker",
            "in every scenario every tracker's mean GOSPA is below that of reporting no target "
            "(sqrt(mean c^2 n_t / 2))",
            empty,
            worst,
            "worst tracker < empty",
            all(worst[s] < empty[s] for s in empty),
        ),
    ]


def make_claims(df: pd.DataFrame, opts: Options, quick: bool) -> list[Claim]:
    k = 3.0 if quick else 2.0
    return [
        *_diagnostic_claims(df, opts, k),
        *_comparison_claims(df, k),
        *_cardinality_claims(df, k, opts.settle),
    ]
