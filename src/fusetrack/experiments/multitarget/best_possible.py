"""The best possible beside ``multitarget-bearings``' table (issue 19, item 3): the oracle floor of
:mod:`.gospa_floor` and the clairvoyant filter of :mod:`.clairvoyant`, against every tracker.

Everything is compared in m² as the mean over runs of each run's ``mean_t d_t^2`` (a tracker's
localisation + missed + false, the floor's Eq. (2) summed), paired by run: a claim holds when
the mean over runs of ``tracker - floor`` is above ``-MARGIN_SE`` standard errors. Trackers are
held to the *whole-run* floor (their confirmations and MCMCDA's decisions use later scans), the
clairvoyant filter, which sees the bearings up to each scan only, to the *online* one.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from ...evaluation import MARGIN_SE, Claim, gospa_over_time, mean_with_se
from .claims import claim
from .clairvoyant import clairvoyant_tracks
from .gospa_floor import entry_prior_cov, run_floors
from .methods import METHODS
from .scenario import Scene, Truth
from .scoring import estimate_sets

ARRAYS = (2, 3)
NEAR = 1.5
"""The clairvoyant filter comes within this factor of the online floor (else the floor is too
low to be called the best possible)."""


def best_possible_columns(
    scene: Scene, truth: Truth, c: float, duration: float, rng: np.random.Generator
) -> dict[str, float]:
    """One run's floors and the clairvoyant filter's ``mean_t d_t^2`` (m²)."""
    priors = entry_prior_cov(scene, truth.positions.shape[1], float(duration))
    floors = run_floors(scene, truth, c, priors)
    est = estimate_sets(clairvoyant_tracks(scene, truth, priors, rng), truth.times)
    g = gospa_over_time(est, [truth.positions[k] for k in range(truth.times.size)], c=c)
    return {
        "floor_online": floors["online"],
        "floor_whole_run": floors["whole_run"],
        "clairvoyant": g.run_distance**2,
    }


def _per_run(df: pd.DataFrame, arrays: int, method: str) -> pd.DataFrame:
    """One row per run (by seed order) of one method: its ``mean_t d_t^2`` and the run's floors."""
    d = df[(df.arrays == arrays) & (df.method == method)]
    return d.assign(mean_square=d["localisation"] + d["missed"] + d["false"])


def _fmt(values: pd.Series) -> str:
    mu, se = mean_with_se(values)
    return f"{mu:.3f}" + (f" ± {se:.3f}" if np.isfinite(se) else "")


def best_table(df: pd.DataFrame) -> pd.DataFrame:
    """``mean_t d_t^2`` (m², mean ± s.e. over runs): the floors, the clairvoyant filter and every
    tracker, with each one's ratio to the whole-run floor, per number of arrays."""
    rows: dict[str, dict[str, str]] = {}
    for n in ARRAYS:
        first = _per_run(df, n, METHODS[0])
        floor = first["floor_whole_run"].mean()
        entries = {
            "oracle floor, whole run": first["floor_whole_run"],
            "oracle floor, online": first["floor_online"],
            "clairvoyant UKF, own bearings": first["clairvoyant"],
            **{m: _per_run(df, n, m)["mean_square"] for m in METHODS},
        }
        for label, v in entries.items():
            rows.setdefault(label, {})[f"{n} arrays (m²)"] = _fmt(v)
            rows[label][f"{n} arrays / whole-run floor"] = f"{v.mean() / floor:.1f}"
    return pd.DataFrame.from_dict(rows, orient="index")


def _above(diff: pd.Series) -> bool:
    mu, se = mean_with_se(diff)
    return bool(mu >= -MARGIN_SE * (se if np.isfinite(se) else 0.0))


def best_claims(df: pd.DataFrame) -> list[Claim]:
    """Every tracker above the whole-run floor; the clairvoyant filter between the online floor
    and :data:`NEAR` times it."""
    ratios: dict[str, float] = {}
    ok = True
    for n in ARRAYS:
        for m in METHODS:
            d = _per_run(df, n, m)
            ratio = float(d["mean_square"].mean() / d["floor_whole_run"].mean())
            ratios[f"{m} {n} arrays"] = round(ratio, 3)
            ok &= _above(d["mean_square"] - d["floor_whole_run"])
    clair: dict[str, float] = {}
    near = True
    for n in ARRAYS:
        d = _per_run(df, n, METHODS[0])
        r = float(d["clairvoyant"].mean() / d["floor_online"].mean())
        clair[f"{n} arrays"] = round(r, 3)
        near &= _above(d["clairvoyant"] - d["floor_online"]) and r <= NEAR
    return [
        claim(
            "diagnostic",
            "BP_trackers_above_floor",
            "every tracker's mean GOSPA² (localisation + missed + false) is not below the oracle's "
            "whole-run floor (known association and number of targets, straight paths; "
            "gospa_floor Eq. 2); ours: mean GOSPA² / floor",
            "not in any paper",
            ratios,
            f"tracker - floor >= -{MARGIN_SE:g} s.e. (paired by run), 2 and 3 arrays",
            ok,
        ),
        claim(
            "diagnostic",
            "BP_clairvoyant_attains_floor",
            "a clairvoyant filter (one UKF per target on its own bearings) is not below the "
            f"online floor and within {NEAR:g} times it; ours: its mean GOSPA² / online floor",
            "not in any paper",
            clair,
            f"clairvoyant - floor >= -{MARGIN_SE:g} s.e. and ratio <= {NEAR:g}, 2 and 3 arrays",
            near,
        ),
    ]


def best_text(df: pd.DataFrame, claims: Sequence[Claim], c: float) -> str:
    """The report's "Best possible" section."""
    verdict = "; ".join(f"`{k.id}` {'holds' if k.holds else '**fails**'}" for k in claims)
    near = {k.id: k.holds for k in claims}.get("BP_clairvoyant_attains_floor", False)
    reading = (
        "The clairvoyant filter comes close to the online floor (the floor is nearly attainable); "
        if near
        else "The clairvoyant filter is not within the claim's factor of the online floor; "
    ) + (
        "the gap between it and the best tracker is the price of not knowing which bearing is "
        "whose (and which are clutter)."
    )
    return f"""## Best possible (what no tracker can beat on this model)

The oracle knows how many targets there are, which bearing is whose and which are clutter, and
that the paths are straight: its bound on each target's position is the Cramér-Rao bound of that
target's own bearings (P_D as an information reduction factor, the model's entry spread as its
prior; `multitarget/gospa_floor.py`). Any estimate set has `d_t² >= Σ_i min(D_i², c²/2) + (c²/2)
max(m - n, 0)` (`D_i`: target i's distance to its nearest estimate), and for errors at least as
wide as the bound (centred Gaussian, covariance at least `B`; not so where two targets come
within a few bound-σ of each other and one's nearest estimate is the other's)
`E min(D_i², c²/2) >= tr B - ((tr B)² + 2 tr B²) / (2c²)` (c = {c:g} m): the
floor on the mean over scans of GOSPA² (m², all of it localisation for the oracle). It bounds the
sum localisation + missed + false of the table above, a mean over runs of means over scans, not
the `gospa` column (a mean of per-run roots can lie below the root of a mean). *Whole run*: from
every bearing of the run (trackers confirm and MCMCDA decides with later scans); *online*: up to
each scan. The clairvoyant filter runs the oracle's data (each target's own labelled bearings, no
clutter, no merging, drawn on the run's paths). Mean ± s.e. over runs:

{best_table(df).to_markdown()}

{verdict}. {reading}
"""


__all__ = ["best_claims", "best_possible_columns", "best_table", "best_text"]
