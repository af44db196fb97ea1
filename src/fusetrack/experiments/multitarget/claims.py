"""The claims of ``multitarget-bearings``: hypotheses of our own, each of which can fail.

Every claim has a kind (``summary.json``'s ``beyond_the_paper.claim_kinds``, and the first
words of its statement): ``beyond`` (a comparison of methods beyond the papers) or
``diagnostic`` (a check of the set-up under our reading). No paper prints these numbers: the
``paper`` column says what was expected before the run.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import Claim

METRICS = (
    "gospa",
    "localisation",
    "missed",
    "false",
    "ospa2",
    "id_switches",
    "mota",
    "n_tracks",
    "ghost_tracks",
)
KIND_PREFIX = {"beyond": "beyond the paper: ", "diagnostic": "our diagnostic: "}


def mean_se(df: pd.DataFrame, arrays: int, method: str, metric: str) -> tuple[float, float]:
    """Mean and standard error over runs of one metric (SE 0 for a single run)."""
    v = df[(df.arrays == arrays) & (df.method == method)][metric].astype(float).to_numpy()
    se = float(v.std(ddof=1) / np.sqrt(v.size)) if v.size > 1 else 0.0
    return float(v.mean()), se


def summary_table(df: pd.DataFrame) -> pd.DataFrame:
    """``mean ± SE`` of every metric, one row per (arrays, method)."""
    rows = []
    for (arrays, method), _ in df.groupby(["arrays", "method"], sort=False):
        row: dict[str, Any] = {"arrays": arrays, "method": method}
        for m in METRICS:
            mu, se = mean_se(df, int(arrays), str(method), m)
            row[m] = f"{mu:.2f} ± {se:.2f}"
        rows.append(row)
    return pd.DataFrame(rows).set_index(["arrays", "method"])


def claim(
    kind: str, cid: str, statement: str, expected: Any, ours: Any, tol: str, holds: bool
) -> Claim:
    return Claim(cid, KIND_PREFIX[kind] + statement, expected, ours, tol, bool(holds), kind)


def claim_kinds(claims: Sequence[Claim]) -> dict[str, str]:
    """``id -> kind`` read back from the statements' prefixes."""
    out = {}
    for c in claims:
        out[c.id] = next(k for k, p in KIND_PREFIX.items() if c.statement.startswith(p))
    return out


def _ghost_claims(df: pd.DataFrame) -> list[Claim]:
    """Triangulation makes ghosts, and three arrays should resolve them."""
    true2, _ = mean_se(df, 2, "JPDA", "true_candidates")
    ghost2, _ = mean_se(df, 2, "JPDA", "ghost_candidates")
    false = {
        f"{m} {n} arrays": mean_se(df, n, m, "false")[0]
        for m in ("GNN", "JPDA", "grid+JPDA")
        for n in (2, 3)
    }
    return [
        claim(
            "diagnostic",
            "ghost_candidates_outnumber_true",
            "with 2 arrays, triangulation gives more ghost (or clutter) candidates per scan than true ones",
            "n(n-1) ghosts vs n true per pair of arrays",
            {"true": true2, "ghost": ghost2},
            "none",
            ghost2 > true2,
        ),
        claim(
            "beyond",
            "three_arrays_fewer_false_tracks",
            "with 3 arrays the GOSPA false-track component is lower than with 2 (ghosts resolved), "
            "for GNN, JPDA and grid+JPDA",
            "false(3 arrays) < false(2 arrays)",
            false,
            "none",
            all(
                false[f"{m} 3 arrays"] < false[f"{m} 2 arrays"]
                for m in ("GNN", "JPDA", "grid+JPDA")
            ),
        ),
    ]


def _method_claims(df: pd.DataFrame, quick: bool) -> list[Claim]:
    """JPDA against GNN, MCMCDA against JPDA, direct tracking's ghosts."""
    k = 3.0 if quick else 2.0
    jg = {
        f"{n} arrays": [mean_se(df, n, "JPDA", "gospa"), mean_se(df, n, "GNN", "gospa")]
        for n in (2, 3)
    }
    mj = {
        f"{n} arrays": [mean_se(df, n, "MCMCDA", "gospa"), mean_se(df, n, "JPDA", "gospa")]
        for n in (2, 3)
    }
    ghosts = {
        f"{m} {n} arrays": mean_se(df, n, m, "ghost_tracks")[0]
        for m in ("direct", "JPDA")
        for n in (2, 3)
    }
    return [
        claim(
            "beyond",
            "jpda_not_worse_than_gnn",
            "JPDA's GOSPA is at most GNN's plus k SE (k in the tolerance column; SE of the two means combined), 2 and 3 arrays",
            "JPDA <= GNN",
            jg,
            f"{k:g} SE",
            all(j[0] <= g[0] + k * np.hypot(j[1], g[1]) for j, g in jg.values()),
        ),
        claim(
            "beyond",
            "mcmcda_not_worse_than_jpda",
            "MCMCDA on the same candidates has GOSPA at most JPDA's plus k SE, 2 and 3 arrays",
            "MCMCDA <= JPDA",
            mj,
            f"{k:g} SE",
            all(m[0] <= j[0] + k * np.hypot(m[1], j[1]) for m, j in mj.values()),
        ),
        claim(
            "beyond",
            "direct_bearings_no_ghost_tracks",
            "tracking the bearings directly (no triangulation) confirms no ghost track: fewer than "
            "0.5 per run (a track whose median distance to the nearest target exceeds the MOT "
            "threshold), 2 and 3 arrays",
            "0 ghost tracks",
            ghosts,
            "< 0.5 per run",
            ghosts["direct 2 arrays"] < 0.5 and ghosts["direct 3 arrays"] < 0.5,
        ),
    ]


def _identity_claims(df: pd.DataFrame, quick: bool) -> list[Claim]:
    """Identity: the soft associators on the bearings keep identities through crossings."""
    k = 3.0 if quick else 2.0
    sw = {f"{m} 3 arrays": mean_se(df, 3, m, "id_switches") for m in ("GNN", "JPDA", "direct")}
    d, j = sw["direct 3 arrays"], sw["JPDA 3 arrays"]
    return [
        claim(
            "beyond",
            "direct_fewest_id_switches",
            "with 3 arrays, direct bearing tracking has no more identity switches (CLEAR MOT) than "
            "JPDA on triangulated points, within k SE",
            "direct <= JPDA",
            sw,
            f"{k:g} SE",
            d[0] <= j[0] + k * np.hypot(d[1], j[1]),
        )
    ]


def make_claims(df: pd.DataFrame, quick: bool) -> list[Claim]:
    return [*_ghost_claims(df), *_method_claims(df, quick), *_identity_claims(df, quick)]
