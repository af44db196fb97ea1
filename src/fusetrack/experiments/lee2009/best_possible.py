"""The best possible beside Lee 2009 Ch. 3's tables (issue 19, item 3): the CRLB of
:mod:`.bearing_bound` against our filters and the paper's numbers.

**Comparisons.** The bound bounds each step's mean-square error, so our filters are compared by
their RMS over runs (the root of the mean over runs of each run's mean square error over its
steps, :func:`~fusetrack.evaluation.rms_over_runs`) with ``sqrt(mean over runs and steps of
trace B_k[pos])`` (the *RMS bound*). The paper prints the mean over runs of each run's RMS (or
one run's), which can lie below a root-mean-square bound. Assuming the errors are centred
Gaussian with covariance at least the bound (exact for an efficient estimator of the linearised
model), a run's mean square error ``S = e^T A e`` is a Gaussian quadratic form, ``E[S^2] <= 3
E[S]^2``, and Hölder's inequality gives ``E[sqrt S] >= E[S]^{3/2} / E[S^2]^{1/2} >= sqrt(E[S] /
3)``: the *mean-RMS bound* is the RMS bound over ``sqrt(3)`` (tight only when one error
direction dominates the whole run). A paper number below it is judged *impossible on the printed
model* (or under the named reading where the text leaves the model open) by
:func:`~fusetrack.evaluation.possible_claim`; a mean over 100 runs fluctuates little about its
expectation, a single run's RMS may fall below it by chance.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from ...evaluation import MARGIN_SE, Claim, ClaimKinds, possible_claim, rms_over_runs

MEAN_FACTOR = 1.0 / math.sqrt(3.0)
"""The mean-RMS bound over the RMS bound (Gaussian errors, module docstring)."""
OBJECTS = ("O1", "O2", "O3")


def summarise(rows: pd.DataFrame, keys: Sequence[str]) -> pd.DataFrame:
    """Per ``keys`` and object, from per-run rows (``rms``, ``bound_ms``): our RMS over runs and
    its s.e., our mean over runs, the RMS bound and the mean-RMS bound (m); an ``average`` row
    per group is the mean over the objects, as the paper's "total average"."""
    out = []
    for key, g in rows.groupby([*keys, "object"], sort=True):
        rms, se = rms_over_runs(g["rms"].to_numpy())
        bound = float(np.sqrt(g["bound_ms"].mean()))
        out.append(
            dict(zip([*keys, "object"], key if isinstance(key, tuple) else (key,), strict=True))
            | {"ours RMS": rms, "s.e.": se, "ours mean": float(g["rms"].mean()),
               "RMS bound": bound, "mean-RMS bound": bound * MEAN_FACTOR}
        )  # fmt: skip
    tab = pd.DataFrame(out)
    avg = tab.groupby(list(keys), sort=False).mean(numeric_only=True).reset_index()
    avg["object"], avg["s.e."] = "average", np.nan
    return pd.concat([tab, avg], ignore_index=True).sort_values([*keys, "object"], kind="stable")


def above_claim(kinds: ClaimKinds, claim_id: str, what: str, tab: pd.DataFrame) -> Claim:
    """Diagnostic: our RMS over runs is not more than :data:`MARGIN_SE` standard errors below
    the RMS bound in every row of ``tab`` (:func:`summarise`) with a bound. Fails only if a
    filter or the bound is wrong."""
    t = tab[(tab["object"] != "average") & tab["RMS bound"].notna()]
    se = t["s.e."].fillna(0.0)
    ok = bool((t["ours RMS"] >= t["RMS bound"] - MARGIN_SE * se).all())
    ratio = float((t["ours RMS"] / t["RMS bound"]).min())
    return kinds.claim(
        claim_id,
        f"{what}: our RMS position error is not below the CRLB of the simulated model (known "
        "association and manoeuvre schedule); ours: smallest RMS / bound",
        "not in the thesis",
        round(ratio, 3),
        f"RMS >= bound - {MARGIN_SE:g} s.e. in every row",
        ok,
    )


def paper_claims(
    kinds: ClaimKinds,
    prefix: str,
    what: str,
    paper: Mapping[str, float],
    bounds: Mapping[str, float],
    model: str = "",
) -> list[Claim]:
    """:func:`~fusetrack.evaluation.possible_claim` per object: the paper's ``paper[object]``
    against the mean-RMS bound ``bounds[object]`` (m), on the printed model or the reading
    ``model``."""
    return [
        possible_claim(
            kinds,
            f"{prefix}_{obj}",
            f"{what} {obj} (the bound: the CRLB's mean-RMS bound, Gaussian errors)",
            float(value),
            (float("nan"), float("nan")),
            round(float(bounds[obj]), 4),
            model,
        )
        for obj, value in paper.items()
    ]


def verdicts(claims: Sequence[Claim]) -> str:
    """``id: verdict`` per claim, for the report text."""
    return "; ".join(f"`{c.id}` {'holds' if c.holds else '**fails**'}" for c in claims)


def md(tab: pd.DataFrame) -> str:
    return str(tab.to_markdown(index=False, floatfmt=".3f"))


__all__ = ["MEAN_FACTOR", "above_claim", "md", "paper_claims", "summarise", "verdicts"]
