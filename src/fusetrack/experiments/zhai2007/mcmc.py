"""Zhai 2007, E19 (Sec. 6.1.2, Table 15): particle filters with MCMC moves after resampling.

Model (Eqs. 93-94): ``x_t = 1.7 exp(-2 x_{t-1}^2) + 5 cos(x_{t-1}) + w``, ``y_t = x_t^2 + v``,
``x_0 ~ N(0, 0.5)``, ``w ~ N(0, 8)``, ``v ~ N(0, 0.5)``, 25 steps. Four filters, all with the
bootstrap proposal: PF; PF-MH (transition prior as instrumental density); PF-RWM (N(0, 0.2) steps);
PF-MIS (N(0, 0.15) independence proposal). Average MSE over runs and time, N in {100, 200, 500, 1000}.
The thesis used 50 runs; ``y = x^2`` hides the sign, so the spec asks for >= 500 runs and CIs.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from functools import partial
from typing import Any

import numpy as np
import pandas as pd

from ...core import Gaussian
from ...evaluation import Claim, ClaimKinds, Outcome, RunContext, plots, run_seed
from ...filters import IndependenceMove, MHPriorMove, ProposalParticleFilter, RandomWalkMove
from ...motion import ScalarBenchmark
from ...sensors import Power
from . import best_possible as bp
from . import scalar
from .common import join_with_relations, timed_sis
from .comparators import UPF_NOTE, Comparison, Scenario, run_comparators
from .equal_time import EqualTime

STEPS = 25
NS = (100, 200, 500, 1000)
METHODS = ("PF", "PF-MH", "PF-RWM", "PF-MIS")
PAPER = pd.DataFrame(
    {
        "PF": [5.3494, 5.0470, 4.3868, 3.4414],
        "PF-MH": [4.8779, 4.0194, 3.3737, 3.3238],
        "PF-RWM": [3.5558, 3.3813, 3.2536, 3.1814],
        "PF-MIS": [3.7227, 3.5506, 3.3580, 3.2574],
    },
    index=list(NS),
)
PAPER_ORDER = ["PF-RWM", "PF-MIS", "PF-MH", "PF"]  # ascending MSE in every row of Table 15


def model() -> tuple[ScalarBenchmark, Power, Gaussian]:
    """Motion (Eq. 93), sensor (Eq. 94) and prior of E19."""
    return (
        ScalarBenchmark(a=1.7, b=5.0, trig="cos", q=8.0),
        Power("y", exponent=2, sigma=float(np.sqrt(0.5))),
        Gaussian(np.zeros(1), 0.5 * np.eye(1)),
    )


def simulate(rng: np.random.Generator) -> tuple[np.ndarray, list[list[np.ndarray]]]:
    """``x_0`` from the prior, then ``STEPS`` transitions and measurements."""
    motion, sensor, prior = model()
    return scalar.simulate(motion, sensor, rng, STEPS, x0=prior.sample(rng))


def make_filter(method: str, n: int) -> ProposalParticleFilter:
    motion, sensor, _ = model()
    move = {
        "PF": None,
        "PF-MH": MHPriorMove(),
        "PF-RWM": RandomWalkMove(variance=0.2),
        "PF-MIS": IndependenceMove(variance=0.15),
    }[method]
    return ProposalParticleFilter(motion, [sensor], n_particles=n, move=move)


def comparator_scenario(seed: int) -> Scenario:
    """Run ``seed``'s truth and measurements as a :class:`Scenario` (one model: IMM = EKF)."""
    truth, zs = simulate(np.random.default_rng(seed))
    motion, sensor, prior = model()
    return Scenario(motion, [sensor], prior, zs, 1.0, truth)


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    truth, zs = simulate(np.random.default_rng(seed))
    _, _, prior = model()
    n = int(config["n_particles"])
    rows = []
    if "n_equal" in config:  # beyond the paper
        for method, timed in run_comparators(
            comparator_scenario(seed), seed, config["n_equal"]
        ).items():
            err2 = (timed.estimates[:, 0] - truth[:, 0]) ** 2
            err2 = np.where(np.isfinite(err2), err2, 1e12)
            rows.append({"method": method, "mse": float(err2.mean()), "seconds": timed.seconds})
    for k, method in enumerate(METHODS):
        filt = make_filter(method, n)
        est, secs, _ = timed_sis(filt, prior, zs, 1.0, np.random.default_rng([seed, k]))
        err2 = (est[:, 0] - truth[:, 0]) ** 2
        rows.append(
            {
                "method": method,
                "mse": float(err2.mean()),
                "seconds": secs,
                "acceptance": filt.stats.acceptance_rate,
                "zero_acceptance_steps": filt.stats.zero_acceptance_steps,
            }
        )
    return rows


POSTERIOR_MEAN = "posterior mean"


def run_best(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """The best possible on run ``seed``'s truth (issue 19): the posterior mean's MSE."""
    truth, zs = simulate(np.random.default_rng(seed))
    motion, sensor, prior = model()
    rng = np.random.default_rng([seed, 1000])
    est, secs = bp.posterior_mean(motion, [sensor], prior, zs, 1.0, config["n_best"], rng)
    mse = float(np.mean((est[:, 0] - truth[:, 0]) ** 2))
    return [{"method": POSTERIOR_MEAN, "mse": mse, "seconds": secs}]


def pcrb_mse(seed: int, n_truths: int) -> float:
    """The PCRB on the average MSE over the 25 steps, over ``n_truths`` truths of Eq. 93."""
    motion, sensor, prior = model()
    rng = np.random.default_rng([seed, 19])
    x0 = np.sqrt(0.5) * rng.standard_normal((n_truths, 1))
    x = bp.simulate_many(lambda x, r: motion.sample(x, 1.0, r), x0, STEPS, rng)
    return float(np.mean(bp.pcrb_rms(motion, [sensor], x, 1.0, prior.cov, [0]) ** 2))


def run(ctx: RunContext) -> Outcome:
    """E19: comparators calibrated to PF-RWM(N), the runs per N, claims, figures, report."""
    runs = ctx.n_runs(full=1000, quick=40)
    cs = comparator_scenario(run_seed(ctx.seed, 0))
    eq = EqualTime.for_run(ctx)
    for n in NS:  # UPF and bootstrap at PF-RWM(N)'s time
        eq.calibrate_sis(n, cs, partial(make_filter, "PF-RWM", n))
    df_all = ctx.monte_carlo(
        run_once, [{"n_particles": n, "n_equal": eq.n_particles[n]} for n in NS], runs
    )
    df = df_all[df_all["method"].isin(METHODS)]
    cmp = comparison(ctx, df_all, eq)
    tab = summarise(df)
    claims = claims_table15(df, tab)
    n_best = bp.best_n(ctx.quick)
    best = ctx.monte_carlo(run_best, [{"n_best": n_best}], runs, desc="best")
    bound = pcrb_mse(ctx.seed, 200 if ctx.quick else 2000)
    best_claims, best_text = best_possible(best, bound, n_best)
    claims += best_claims
    figs = figures(ctx, tab, runs)
    body = report_text(tab, runs, figs, claims) + best_text + cmp.section
    return Outcome(df_all, claims, body, runs, beyond_the_paper=cmp.summary)


def comparison(ctx: RunContext, df_all: pd.DataFrame, eq: EqualTime) -> Comparison:
    """Beyond the paper: UPF, bootstrap at PF-RWM's time and the EKF, per N."""
    return eq.compare(
        df_all.assign(error=df_all["mse"]),
        "PF-RWM",
        ctx.figure_path("error_vs_seconds_comparators"),
        by=["n_particles"],
        ylabel="average MSE",
        notes=[
            "IMM-EKF: the model has one motion model and a one-model IMM is exactly the EKF; "
            "with y = x^2 and a prior centred on 0 the EKF's Jacobian 2x starts at 0, so it "
            "cannot learn the sign.",
            UPF_NOTE,
            "n_particles is the particle count of the paper's four filters; the comparators' "
            "counts are the calibrated ones above.",
        ],
    )


def summarise(df: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """Per N and method (columns in :data:`METHODS` order): mean MSE, its standard error, the
    MH acceptance rate and the seconds per run."""
    g = df.groupby(["n_particles", "method"])
    return {
        "mse": g["mse"].mean().unstack("method")[list(METHODS)],
        "se": (g["mse"].std() / np.sqrt(g["mse"].count())).unstack("method")[list(METHODS)],
        "acc": g["acceptance"].mean().unstack("method")[list(METHODS)],
        "secs": g["seconds"].mean().unstack("method")[list(METHODS)],
    }


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "mis_acceptance_reported": "diagnostic",  # the thesis does not report it
        "BP_*": "diagnostic",  # Table 15 against the best possible (issue 19)
        "C15_*": "paper",
    }
)


def claims_table15(df: pd.DataFrame, tab: Mapping[str, pd.DataFrame]) -> list[Claim]:
    """C15: Table 15's ordering per N, the moves' paired gain over the PF, the PF's MSE falling
    with N, and the MIS acceptance rate."""
    mse = tab["mse"]
    claims: list[Claim] = []
    for n in NS:
        claims.append(
            CLAIM_KINDS.claim(
                f"C15_order_N{n}",
                f"N={n}: MSE PF > PF-MH > PF-MIS > PF-RWM (Table 15)",
                " > ".join(f"{m} {PAPER.loc[n, m]:.3f}" for m in reversed(PAPER_ORDER)),
                join_with_relations(
                    [float(mse.loc[n, m]) for m in reversed(PAPER_ORDER)],
                    [f"{m} {mse.loc[n, m]:.3f}" for m in reversed(PAPER_ORDER)],
                ),
                "strict ordering of means",
                all(mse.loc[n, a] < mse.loc[n, b] for a, b in itertools.pairwise(PAPER_ORDER)),
            )
        )
    claims += claims_paired_gain(df)
    falls = all(mse.loc[a, "PF"] > mse.loc[b, "PF"] for a, b in itertools.pairwise(NS))
    claims.append(
        CLAIM_KINDS.claim(
            "C15_pf_falls_with_n",
            "the PF's MSE falls as N grows (Table 15, column PF)",
            ", ".join(f"{v:.3f}" for v in PAPER["PF"]),
            ", ".join(f"{v:.3f}" for v in mse["PF"]),
            "strictly decreasing",
            falls,
        )
    )
    mis_acc = float(tab["acc"]["PF-MIS"].mean())
    claims.append(
        CLAIM_KINDS.claim(
            "mis_acceptance_reported",
            "the MIS with N(0, 0.15) proposals has a low acceptance rate (spec Sec. 3, Alg. 10)",
            "not reported",
            mis_acc,
            "< 0.2",
            mis_acc < 0.2,
        )
    )
    return claims


def best_possible(best: pd.DataFrame, bound: float, n_best: int) -> tuple[list[Claim], str]:
    """Issue 19: Table 15 against the posterior mean's MSE (``best``: its runs, ``n_best``
    particles) and the PCRB ``bound``: a claim for the table's smallest entry, the section."""
    value, se = bp.mean_with_se(best["mse"])
    n, m = min(((n, m) for n in NS for m in METHODS), key=lambda k: PAPER.loc[k[0], k[1]])
    verdicts = PAPER.apply(lambda col: col.map(lambda v: bp.verdict(v, value, se, bound)))
    claim = bp.possible_claim(
        CLAIM_KINDS,
        "BP_possible_table15",
        f"Table 15's smallest entry ({m}, N = {n}; average MSE)",
        float(PAPER.loc[n, m]),
        (value, se),
        bound,
    )
    outcome = (
        "Every entry lies at or above the best possible, so the model does not rule Table 15 "
        "out; its ordering is a matter of Monte Carlo noise (see the differences above)."
        if claim.holds
        else f"Table 15's {m} at N = {n} lies below it: *{bp.IMPOSSIBLE}*."
    )
    return (
        [claim],
        f"""
## The best possible beside Table 15

What no filter can beat on Eqs. 93-94, on the same truths and measurements: the posterior mean
(a bootstrap filter with {n_best} particles) has an average MSE of **{value:.3f} ± {se:.3f}**; the
PCRB (over truths drawn from the model; it ignores the sign ambiguity of `y = x^2`, so it is
loose) is {bound:.3f}. Each Table 15 entry against them (*{bp.IMPOSSIBLE}*: more than
{bp.MARGIN_SE:g} standard errors below the posterior mean, or below the PCRB):

{verdicts.to_markdown()}

{outcome}
""",
    )


def claims_paired_gain(df: pd.DataFrame) -> list[Claim]:
    """PF-MH and PF-RWM reduce the PF's MSE at every N (paired differences: common random
    numbers give every method the same truth per run)."""
    wide = df.pivot_table(index=["n_particles", "run"], columns="method", values="mse")
    claims = []
    for m in ("PF-MH", "PF-RWM"):
        diff = wide["PF"] - wide[m]
        d = diff.groupby(level=0)
        mean_d, se_d = d.mean(), d.std() / np.sqrt(d.count())
        z = (mean_d / se_d).min()
        claims.append(
            CLAIM_KINDS.claim(
                f"C15_{m}_beats_PF",
                f"{m} reduces the PF's MSE at every N, beyond Monte Carlo noise (paired z > 2)",
                "reduction at every N: "
                + ", ".join(f"{(PAPER.loc[n, 'PF'] - PAPER.loc[n, m]):.3f}" for n in NS),
                "reduction at every N: " + ", ".join(f"{mean_d[n]:.3f}±{se_d[n]:.3f}" for n in NS),
                "paired z > 2 at every N",
                bool(z > 2),
            )
        )
    return claims


def figures(ctx: RunContext, tab: Mapping[str, pd.DataFrame], runs: int) -> dict[str, str]:
    """MSE against N beside Table 15, and MSE against computing time: file names."""
    mse = tab["mse"]
    fig = plots.plot_series(
        ctx.figure_path("mse_vs_particles"),
        np.array(NS),
        {
            **{m: mse[m].to_numpy() for m in METHODS},
            **{f"paper {m}": PAPER[m].to_numpy() for m in METHODS},
        },
        xlabel="particles N",
        ylabel="average MSE",
        title=f"Table 15: ours ({runs} runs) and the paper's (dotted)",
        styles={f"paper {m}": ":" for m in METHODS},
    )
    fig_t = plots.plot_series(
        ctx.figure_path("mse_vs_seconds"),
        tab["secs"]["PF"].to_numpy(),
        {m: mse[m].to_numpy() for m in METHODS},
        xlabel="seconds per run (PF's time at each N on the x-axis)",
        ylabel="average MSE",
        title="MSE against computing time",
    )
    return {"n": fig.name, "t": fig_t.name}


def equal_time_winner(tab: Mapping[str, pd.DataFrame]) -> str:
    """The method with the lowest MSE at PF-RWM's largest cost (interpolated in seconds)."""
    secs, mse = tab["secs"], tab["mse"]
    best_time = {}
    for m in METHODS:
        best_time[m] = float(
            np.interp(float(secs["PF-RWM"].max()), secs[m].to_numpy(), mse[m].to_numpy())
        )
    return min(best_time, key=best_time.get)  # type: ignore[arg-type]


def report_text(
    tab: Mapping[str, pd.DataFrame], runs: int, figs: Mapping[str, str], claims: list[Claim]
) -> str:
    """The report's set-up, Table 15 beside ours, and the differences (comparators follow)."""
    mse, se = tab["mse"], tab["se"]
    table = pd.concat({"paper": PAPER, "ours": mse, "± s.e.": se}, axis=1)
    cost = pd.concat({"seconds/run": tab["secs"], "acceptance": tab["acc"]}, axis=1)
    rows_order = sum(c.holds for c in claims if c.id.startswith("C15_order_N"))
    mis_acc = float(tab["acc"]["PF-MIS"].mean())
    return f"""
## Set-up

Zhai 2007, Eqs. 93-94 as printed; 25 steps; {runs} runs per N (the thesis: 50) with the same truths
for every filter and N (common random numbers). One MH iteration per particle per step, target
`p(y_t|x) p(x|x_(t-1)^(a_i))` (spec choice 28); systematic resampling at every step; estimate =
mean of the (moved) particles; MSE averaged over the 25 steps and the runs.

## Table 15: paper beside ours (± standard error of our mean)

{table.to_markdown(floatfmt=".3f")}

Cost and acceptance (beyond the paper):

{cost.to_markdown(floatfmt=".3f")}

![MSE vs N]({figs["n"]})

![MSE vs time]({figs["t"]})

## Differences and their causes

The paper's ordering PF > PF-MH > PF-MIS > PF-RWM holds in {rows_order} of the 4 rows here. Our
MSE levels ({mse.to_numpy().min():.2f}-{mse.to_numpy().max():.2f}) are of the paper's order
(3.2-5.3) and fall with N, but the four filters differ by amounts comparable to the standard error:
with `y = x^2` the posterior is bimodal in the sign of `x`, and the mean's squared error is
dominated by runs where the filter cannot know the sign, which no MCMC move can fix (the moves
leave the same posterior invariant; they only add diversity). The thesis's 50 runs give a standard
error of roughly {float(se.to_numpy().mean() * np.sqrt(runs / 50)):.2f} on each entry, larger than
most of its differences between columns, so Table 15's ordering is not evidence of an effect. The
MIS proposal N(0, 0.15) hardly ever lands in the posterior (acceptance {mis_acc:.3f}), so PF-MIS
is nearly the plain PF, as the spec predicted. At equal computing time (interpolated at the RWM's
largest cost) the lowest MSE is **{equal_time_winner(tab)}**: a move costs about as much as a second likelihood
evaluation per particle, which buys about as much as doubling N.

"""
