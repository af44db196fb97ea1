"""The best possible beside Fig. 12 (E6, camera selection; issue 19 item 3).

Every method of Fig. 12 reads at most the cameras all of them together read, and knows the
occluders at best through Gaussian priors of them; knowing every camera's reading and the
occluders' exact positions is more information than any of that (Blackwell 1953), so the minimum
mean-square error with all cameras and perfect occluder priors is a floor for every method at
every k. It is estimated by the occlusion-aware tracker itself with all cameras and perfect
priors at L and 2L particles (:mod:`.best_possible`: its estimate converges to the posterior
mean; with perfect priors the tracker's model is the simulation's), on the same worlds; the
room centre is the trivial row. The PCRB does not apply (seen / not-seen reports make the
likelihood discontinuous). The paper prints no values for Fig. 12 (only RMSE_max = 47.9), so no
paper number is judged against the floor; what can fail is a method below it, which only a bug
(or an unconverged floor) makes possible.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

import pandas as pd

from ...evaluation import MARGIN_SE, Claim, ClaimKinds, mean_with_se, not_above
from . import best_possible as bp
from .common import md

POINT = "all-perfect"
"""The best possible's series: all cameras, perfect occluder priors."""
FACTORS = {"full": (1, 2), "quick": (1, 2)}
"""Its particle counts as multiples of L (both run: no Fig. 12 series has perfect priors)."""


def best_configs(all_config: dict[str, Any], counts: tuple[int, int]) -> list[dict[str, Any]]:
    """The "all cameras" configuration with perfect priors at each of ``counts`` particles."""
    point = {**all_config, "prior": "perfect", "metric_gap": False}
    return [{**point, "particles": n, "label": f"{bp.BEST_PREFIX}{n}|{POINT}"} for n in counts]


def estimate(
    runs: pd.DataFrame, best_runs: pd.DataFrame, counts: tuple[int, int], particles: int
) -> bp.BestPossible:
    """Mean RMSE_tr (and s.e.) of the floor at both counts; the room centre from ``runs``."""
    values: dict[tuple[int, Hashable], tuple[float, float]] = {
        (int(n), POINT): mean_with_se(g["rmse_tr"]) for n, g in best_runs.groupby("particles")
    }
    trivial = mean_with_se(runs.groupby("run")["rmse_max"].first())
    return bp.BestPossible(values, counts, particles, trivial)


def method_means(table: pd.DataFrame, runs: int) -> dict[tuple[str, int], tuple[float, float]]:
    """Each (method, k) of Fig. 12's table as (mean, s.e. = std / sqrt(runs))."""
    return {
        (str(r.label), int(r.k)): (float(r.mean), float(r.std) / runs**0.5)
        for r in table.itertuples()
    }


def claims(
    kinds: ClaimKinds, best: bp.BestPossible, means: dict[tuple[str, int], tuple[float, float]]
) -> list[Claim]:
    """No method below the floor (by more than the margin), and the floor converged."""
    floor = best.best(POINT)
    below = sorted(key for key, m in means.items() if not not_above(floor, m))
    margin = f"{MARGIN_SE:g} combined s.e."
    return [
        kinds.claim(
            "BP_no_method_below_floor",
            "no method's mean RMSE_tr at any k is below the best possible (all cameras, perfect "
            f"occluder priors, L = {best.counts[1]}) by more than {margin}: more information "
            "than any method has, so a method below it means a bug or an unconverged floor",
            "every method at or above the floor",
            f"below at {len(below)} of {len(means)} (method, k)"
            + (f": {', '.join(f'{m} k={k}' for m, k in below)}" if below else ""),
            f"none below (within {margin})",
            not below,
        ),
        *bp.converged_claims(
            kinds, best, {POINT: ("all_perfect", "with all cameras and perfect occluder priors")}
        ),
    ]


def section(
    best: bp.BestPossible,
    means: dict[tuple[str, int], tuple[float, float]],
    n_cameras: int,
    runs: int,
) -> str:
    """Report text: the floor beside Fig. 12 and each method's distance from it at each k."""
    n1, n2 = best.counts
    floor = best.best(POINT)
    rows = [
        {"estimator": f"posterior mean, all {n_cameras} cameras, perfect priors (L = {n})"}
        | {"RMSE_tr": "{:.3g} ± {:.2g}".format(*best.values[(n, POINT)])}
        for n in best.counts
    ] + [{"estimator": bp.TRIVIAL, "RMSE_tr": "{:.3g} ± {:.2g}".format(*best.trivial)}]
    ratio = pd.DataFrame(
        [{"label": m, "k": k, "ratio": mean / floor[0]} for (m, k), (mean, _) in means.items()]
    ).pivot(index="k", columns="label", values="ratio")
    return f"""
## The best possible on the printed model

Every method of Fig. 12 reads at most what all {n_cameras} cameras read and knows the occluders
at best through Gaussian priors; all cameras with the occluders' exact positions is more
information (Blackwell 1953), so its minimum mean-square error is a floor for every method at
every k. It is the occlusion-aware tracker itself with all cameras and perfect priors, whose
estimate converges to the posterior mean, at L = {n1} and L = {n2} on the same {runs} worlds
(`BP_converged_all_perfect` checks that the two agree; where they do not, the floor at the larger L is
still an upper estimate of the true one, which only makes `BP_no_method_below_floor` easier to fail); the
room centre is the trivial estimator. The PCRB
does not apply (seen / not-seen reports make the likelihood discontinuous). Mean over runs of
the per-run RMSE_tr ± its standard error:

{md(pd.DataFrame(rows))}

Each method's mean RMSE_tr over the floor (L = {n2}); `BP_no_method_below_floor` checks that none
is below it. Fig. 12 prints no values (only RMSE_max = 47.9), so no paper number is judged here.

{md(ratio.round(2).reset_index())}
"""
