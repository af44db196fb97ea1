"""What no filter can beat, beside a paper's table (issue 19, item 3): the statistics and the
judgement that label a paper number below the best possible *impossible on the printed model*.

The best possible is estimated per experiment (a posterior-mean filter with many particles, a
PCRB, trivial estimators); this module only compares a paper number with it. The posterior mean
``E[x_t | z_1:t]`` minimises every step's mean-square error among all estimators that see the
same measurements and prior (Anderson & Moore 1979, Sec. 2.3), so a paper number more than
:data:`MARGIN_SE` standard errors below it, or below a PCRB (Tichavský, Muravchik & Nehorai
1998), cannot come from the model as printed.

Paper tables give the mean and the variance over runs of the per-run RMSE; the root mean square
over runs, ``sqrt(mean^2 + var)``, is what a mean-square bound bounds (:func:`paper_rms`), and
ours is compared the same way (:func:`rms_over_runs`); a paper that gives only the mean is
compared with our mean (:func:`mean_with_se`).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
import pandas as pd

from ..core import ConfigError, invalid
from .report import Claim, ClaimKinds

MARGIN_SE = 3.0
"""A paper number counts as below the best possible when it is more than this many standard
errors below the posterior mean's value."""
POSSIBLE = "possible"
IMPOSSIBLE = "impossible on the printed model"
NOT_FROM_MODEL = "cannot come from the printed model"


def rms_over_runs(per_run_rmse: pd.Series | np.ndarray) -> tuple[float, float]:
    """``sqrt(mean over runs of RMSE_run^2)`` and its standard error (delta method)."""
    r2 = np.asarray(per_run_rmse, dtype=float) ** 2
    m = float(np.mean(r2))
    se_m = float(np.std(r2, ddof=1) / np.sqrt(len(r2))) if len(r2) > 1 else float("nan")
    root = float(np.sqrt(m))
    return root, se_m / (2.0 * root) if root > 0 else float("nan")


def mean_with_se(values: pd.Series | np.ndarray) -> tuple[float, float]:
    """Mean over runs and its standard error (NaN for one run)."""
    v = np.asarray(values, dtype=float)
    se = float(np.std(v, ddof=1) / np.sqrt(len(v))) if len(v) > 1 else float("nan")
    return float(np.mean(v)), se


def paper_rms(mean: float, var: float) -> float:
    """A paper's root mean square over runs of the per-run RMSE from its mean and variance."""
    return float(np.sqrt(mean**2 + var))


def best_possible_verdict(
    paper: float,
    best: float,
    se: float,
    bound: float | None = None,
    model: str = "",
    better: Literal["lower", "higher"] = "lower",
) -> str:
    """:data:`POSSIBLE`, or :data:`IMPOSSIBLE` (``model``: another reading's name) when
    ``paper`` is below the PCRB ``bound`` or more than :data:`MARGIN_SE` standard errors below
    the posterior mean's ``best`` (a NaN ``se``, one run, counts as 0). With ``better="higher"``
    (a score such as an ISNR, where the best possible is a maximum) the same with "above"."""
    if better not in ("lower", "higher"):
        raise ConfigError(invalid("better", better, "'lower' or 'higher'"))
    sign = 1.0 if better == "lower" else -1.0
    margin = MARGIN_SE * (se if np.isfinite(se) else 0.0)
    below = sign * paper < sign * best - margin or (
        bound is not None and sign * paper < sign * bound
    )
    if not below:
        return POSSIBLE
    return IMPOSSIBLE if not model else f"impossible under '{model}'"


def possible_claim(
    kinds: ClaimKinds,
    claim_id: str,
    what: str,
    paper: float,
    best: tuple[float, float],
    bound: float | None = None,
    model: str = "",
    better: Literal["lower", "higher"] = "lower",
    best_label: str = "posterior mean",
    bound_label: str = "PCRB",
) -> Claim:
    """Diagnostic: the paper's ``what`` (``paper``) is not below the best possible on the
    printed model, or on the reading ``model`` (posterior mean ``best = (value, s.e.)``, or
    what ``best_label`` names, NaN where only the bound is known; ``bound`` the PCRB, or what
    ``bound_label`` names, e.g. a static CRLB); with
    ``better="higher"`` (a score), not above it. Fails: the number is *impossible on the printed
    model*, not merely not reproduced."""
    value, se = best
    label = best_possible_verdict(paper, value, se, bound, model, better)
    pcrb = "" if bound is None else f"{bound_label} {bound:.3g}"
    side, ge, pm = ("below", ">=", "-") if better == "lower" else ("above", "<=", "+")
    if np.isnan(value):
        if bound is None:
            raise ConfigError(invalid("best, bound", (best, bound), "a posterior mean or a PCRB"))
        ours, tolerance = f"{pcrb}: {label}", f"paper {ge} {bound_label}"
    else:
        ours = f"{best_label} {value:.3g} ± {se:.2g}{', ' + pcrb if pcrb else ''}: {label}"
        tolerance = f"paper {ge} {best_label} {pm} {MARGIN_SE:g} s.e. and {ge} {bound_label}"
    return kinds.claim(
        claim_id,
        f"{what}: the paper's number is not {side} the best possible on "
        + (f"the reading '{model}'" if model else "the printed model"),
        paper,
        ours,
        tolerance,
        label == POSSIBLE,
    )


def converged_claim(
    kinds: ClaimKinds,
    claim_id: str,
    what: str,
    paper: float,
    trivial: tuple[str, float],
) -> Claim:
    """Diagnostic for a paper's *bootstrap* row: a bootstrap filter converges to the posterior
    mean, the best possible, so once ours has converged at the paper's particle count the
    paper's row can be no worse than a trivial estimator (``trivial = (label, RMS)``). Fails:
    the paper's level *cannot come from the printed model*."""
    label, value = trivial
    ok = paper <= value
    return kinds.claim(
        claim_id,
        f"{what}: no worse than the trivial estimator '{label}' on the printed model",
        paper,
        f"{label} {value:.3g}: {'consistent' if ok else NOT_FROM_MODEL}",
        "paper <= trivial estimator",
        ok,
    )


def combined_se(*se: float) -> float:
    """The standard error of a difference of independent means, ``hypot`` of theirs (a NaN
    s.e., one run, counts as 0)."""
    return math.hypot(*(float(x) if np.isfinite(x) else 0.0 for x in se))


def not_above(a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Mean ``a = (mean, s.e.)`` is not above mean ``b`` by more than :data:`MARGIN_SE`
    combined standard errors."""
    return a[0] <= b[0] + MARGIN_SE * combined_se(a[1], b[1])


def agreement_claim(
    kinds: ClaimKinds,
    claim_id: str,
    what: str,
    smaller: tuple[int, float, float],
    larger: tuple[int, float, float],
) -> Claim:
    """Diagnostic: a particle filter's error at two large particle counts ``(n, value, s.e.)``
    agrees within :data:`MARGIN_SE` combined standard errors, so the larger count's value is
    the converged one (the posterior mean's). Fails: more particles are still needed."""
    (n1, v1, s1), (n2, v2, s2) = smaller, larger
    ok = bool(abs(v2 - v1) <= MARGIN_SE * combined_se(s1, s2))
    return kinds.claim(
        claim_id,
        f"{what}: converged, the same at {n1} and {n2} particles",
        None,
        f"{v1:.3g} ± {s1:.2g} at {n1}, {v2:.3g} ± {s2:.2g} at {n2}",
        f"abs(difference) <= {MARGIN_SE:g} combined s.e.",
        ok,
    )


def best_table(rows: dict[str, dict[str, float]]) -> pd.DataFrame:
    """The rows beside a paper table, in the given order: ``{label: {column: value}}``."""
    return pd.DataFrame.from_dict(rows, orient="index")


__all__ = [
    "IMPOSSIBLE",
    "MARGIN_SE",
    "NOT_FROM_MODEL",
    "POSSIBLE",
    "agreement_claim",
    "best_possible_verdict",
    "best_table",
    "converged_claim",
    "mean_with_se",
    "paper_rms",
    "possible_claim",
    "rms_over_runs",
]
