"""What no tracker can beat on an Ercan simulation (issue 19, item 3): the rows printed beside a
figure's table, for any points of its grid (E1's prior levels x camera counts, E2's extremes).

On the same simulated runs (same seeds, so the same walkers, camera noise and filter streams):

* **posterior mean**: the same occlusion-aware ASIR (Algorithm 1, the likelihood of Sec. 4 with
  perfect or no occluder priors) with more particles than the paper's L. Its estimate converges
  to the posterior mean of the tracker's model, which minimises every step's mean-square error
  among estimators that see the same readings (Anderson & Moore 1979, Sec. 2.3); it is shown at
  two particle counts whose agreement shows that it has converged. With perfect or no occluder
  priors the tracker's model is the simulation's (up to Eq. 7's approximation); Gaussian priors
  from the random-walk Kalman filters are overconfident, so their large-L limit is no best
  possible and is not run.
* **trivial estimator**: the room centre, whose error is the paper's RMSE_max (Sec. 6).
* **PCRB**: does not apply: the seen / not-seen reports make the likelihood discontinuous in the
  position (Eq. 7's shadows) and the waypoint dynamics switch regimes, so the regularity
  conditions of Tichavský et al. 1998 fail.

The paper's numbers are means over runs of the per-run RMSE_tr, and ours are compared the same
way, with their standard error (:func:`~fusetrack.evaluation.mean_with_se`).
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import pandas as pd

from ...evaluation import (
    IMPOSSIBLE,
    MARGIN_SE,
    POSSIBLE,
    Claim,
    ClaimKinds,
    agreement_claim,
    mean_with_se,
    not_above,
)

BEST_PREFIX = "best L="
"""Label prefix of a posterior-mean run: ``best L=5000|0`` (the sweep point labelled "0")."""
FACTORS = {"full": (2, 5), "quick": (1, 2)}
"""Particle counts of the two posterior-mean series, as multiples of the run's L (a multiple
of 1 reuses the sweep's own runs)."""
TRIVIAL = "room centre (trivial, RMSE_max)"
EXTREMES = {"perfect": "perfect occluder priors", "none": "no occluder priors"}
"""The two prior levels whose posterior mean is a best possible (Gaussian priors' is not)."""


def particle_counts(
    quick: bool, particles: int, factors: Mapping[str, tuple[int, int]] = FACTORS
) -> tuple[int, int]:
    """The two posterior-mean particle counts for a run of ``particles`` (the paper's L)."""
    small, large = factors["quick" if quick else "full"]
    return small * particles, large * particles


def best_configs(
    points: Sequence[dict[str, Any]], counts: Sequence[int], particles: int
) -> list[dict[str, Any]]:
    """The sweep's configurations ``points`` again at every count of ``counts`` other than the
    sweep's own ``particles``."""
    return [
        {**c, "particles": n, "label": f"{BEST_PREFIX}{n}|{c['label']}"}
        for n in counts
        if n != particles
        for c in points
    ]


def is_best(results: pd.DataFrame) -> pd.Series:
    """Which rows of ``results`` belong to a posterior-mean series."""
    return results["label"].str.startswith(BEST_PREFIX)


@dataclass(frozen=True)
class BestPossible:
    """Mean RMSE_tr and its standard error per ``(particles, point)`` (a point: the value of the
    grid column, or the tuple of the grid columns, that names it), the counts, the paper's L and
    the room centre's error (``rmse_max``: mean and s.e. over runs)."""

    values: dict[tuple[int, Hashable], tuple[float, float]]
    counts: tuple[int, int]
    particles: int
    trivial: tuple[float, float]

    def best(self, point: Hashable) -> tuple[float, float]:
        """The posterior mean's RMSE_tr (mean, s.e.) at the larger count."""
        return self.values[(self.counts[1], point)]

    def rows(self, point: Hashable) -> dict[str, tuple[int | None, float, float]]:
        """``{estimator: (particles or None, mean, s.e.)}`` of one point: ours at the paper's L,
        the posterior mean at each other count, the room centre."""
        out: dict[str, tuple[int | None, float, float]] = {
            "ours at the paper's L": (self.particles, *self.values[(self.particles, point)])
        }
        for n in (n for n in self.counts if n != self.particles):
            out[f"posterior mean (L = {n})"] = (n, *self.values[(n, point)])
        return out | {TRIVIAL: (None, *self.trivial)}


def estimate(
    sweep: pd.DataFrame,
    best_runs: pd.DataFrame,
    counts: tuple[int, int],
    particles: int,
    by: str | Sequence[str],
) -> BestPossible:
    """The best-possible rows from the sweep's runs ``sweep`` (at the paper's L) and the
    posterior-mean runs ``best_runs``, per point named by the column(s) ``by``; only the points
    rerun in ``best_runs`` are kept. The room centre's error is one value per run."""
    cols = [by] if isinstance(by, str) else list(by)
    points = best_runs[cols].drop_duplicates()
    base = sweep.merge(points, on=cols).assign(particles=particles)
    both = pd.concat([base, best_runs])
    values = {}
    for key, g in both.groupby(["particles", *cols], sort=False):
        n, *point = key
        values[(int(n), point[0] if isinstance(by, str) else tuple(point))] = mean_with_se(
            g["rmse_tr"]
        )
    trivial = mean_with_se(sweep.groupby("run")["rmse_max"].first())
    return BestPossible(values, counts, particles, trivial)


def converged_claims(
    kinds: ClaimKinds, bp: BestPossible, points: Mapping[Hashable, tuple[str, str]]
) -> list[Claim]:
    """``BP_converged_{suffix}`` for each ``point -> (suffix, "with ...")``: the posterior mean
    at the two counts agrees, so the larger count's value is the converged one."""
    n1, n2 = bp.counts
    return [
        agreement_claim(
            kinds,
            f"BP_converged_{suffix}",
            f"posterior-mean RMSE_tr {what}",
            (n1, *bp.values[(n1, point)]),
            (n2, *bp.values[(n2, point)]),
        )
        for point, (suffix, what) in points.items()
    ]


def intro(bp: BestPossible, runs: int) -> str:
    """The opening of a best-possible section: what is shown and why no PCRB applies."""
    n1, n2 = bp.counts
    return f"""## The best possible on the printed model

What no tracker can beat on these {runs} runs (issue 19): the same occlusion-aware tracker with
L = {n1} and L = {n2} particles (the paper's L = {bp.particles}), whose estimate converges to the
posterior mean of the tracker's model, and the room centre (the trivial estimator, RMSE_max).
The PCRB does not apply (seen / not-seen reports make the likelihood discontinuous, the dynamics
switch regimes)."""


def grid_ks(best: BestPossible) -> list[int]:
    """The camera counts rerun for the best possible of a grid (points ``(prior, k)``)."""
    return sorted({int(point[1]) for _, point in best.values})  # type: ignore[index]


def gaussian_ours(df: pd.DataFrame, ks: Sequence[int]) -> dict[int, tuple[float, float]]:
    """Our Gaussian-prior tracker's mean RMSE_tr at the paper's L and its s.e., per ``k``."""
    gauss = df[df["prior"] == "gaussian"]
    return {k: mean_with_se(gauss.loc[gauss["k"] == k, "rmse_tr"]) for k in ks}


def grid_claims(
    kinds: ClaimKinds,
    best: BestPossible,
    gaussian: Mapping[int, tuple[float, float]],
    claim: str,
    extremes: Mapping[str, str],
    gaussian_what: str = "Gaussian priors",
    suffix: str = "",
) -> list[Claim]:
    """Diagnostics of a prior x camera-count grid (``claim``: the paper's ordering claim, e.g.
    C3 on Fig. 6) against the best possible: the paper's ordering is possible (the posterior
    mean with perfect priors is not above the one with none), our Gaussian-prior tracker does
    not lose to the no-prior best possible, and the posterior mean has converged.

    Knowing the occluders exactly is more information than noisy priors of them, which are more
    than none, so on the printed model the minimum mean-square errors are ordered
    perfect <= Gaussian <= none (Blackwell 1953): the paper's ordering needs the two extremes'
    posterior means in that order, and a Gaussian-prior tracker above the no-prior one makes its
    priors worse than no information. ``gaussian``: that tracker's (mean, s.e.) per camera count
    (``gaussian_what``: which Gaussian priors, where a grid has several; ``suffix``: appended to
    the ordering claims' ids, where one report judges several grids)."""
    ks = grid_ks(best)
    ordered = [k for k in ks if not_above(best.best(("perfect", k)), best.best(("none", k)))]
    label = POSSIBLE if len(ordered) == len(ks) else IMPOSSIBLE
    within = [k for k in ks if not_above(gaussian[k], best.best(("none", k)))]
    margin = f"{MARGIN_SE:g} combined s.e."
    n2 = best.counts[1]
    return [
        kinds.claim(
            f"BP_ordering_possible{suffix}",
            f"{claim}'s ordering perfect <= Gaussian <= none needs the best possible in that order (on "
            "the printed model the minimum mean-square errors are, since exact occluder positions "
            "are more information than noisy or none): the posterior mean with perfect priors is "
            f"not above the one with no priors (L = {n2}) by more than {margin}, at k in {ks}",
            "perfect <= Gaussian <= none at every camera count",
            f"in order at {len(ordered)} of {len(ks)} camera counts: {label}",
            f"all camera counts (within {margin})",
            len(ordered) == len(ks),
        ),
        kinds.claim(
            f"BP_gaussian_not_above_no_prior_best{suffix}",
            f"our tracker with {gaussian_what} (L = "
            f"{best.particles}) is not above the best possible without occluder priors (L = {n2}) "
            f"by more than {margin} (else its priors are worse than no information), at k in {ks}",
            "Gaussian <= none at every camera count",
            f"not above at {len(within)} of {len(ks)} camera counts",
            f"all camera counts (within {margin})",
            len(within) == len(ks),
        ),
        *converged_claims(
            kinds,
            best,
            {
                (p, k): (f"{p}_k{k}", f"with {extremes[p]}, k = {k} cameras")
                for p in extremes
                for k in ks
            },
        ),
    ]


def grid_rows(
    best: BestPossible, gaussian: Mapping[int, tuple[float, float]], extremes: Mapping[str, str]
) -> pd.DataFrame:
    """The best-possible rows beside a prior x camera-count table (Figs. 6 and 14): per camera
    count, ours at the paper's L and the posterior mean at each larger count (mean ± s.e.) for
    the two ``extremes`` and ours with Gaussian priors, and the room centre."""
    ks = grid_ks(best)
    rows: list[dict[str, Any]] = []
    for k in ks:
        rows_k = {p: best.rows((p, k)) for p in extremes}
        for name, (n, _, _) in rows_k["perfect"].items():
            if name == TRIVIAL:
                continue
            cell = {p: "{1:.3g} ± {2:.2g}".format(*rows_k[p][name]) for p in extremes}
            gauss = "{:.3g} ± {:.2g}".format(*gaussian[k]) if n == best.particles else "–"
            rows.append(
                {"k": k, "estimator": name, "particles": str(n), "perfect": cell["perfect"]}
                | {"gaussian": gauss, "none": cell["none"]}
            )
    centre = "{:.3g} ± {:.2g}".format(*best.trivial)
    rows.append(
        {"k": "any", "estimator": TRIVIAL, "particles": ""}
        | {p: centre for p in ("perfect", "gaussian", "none")}
    )
    return pd.DataFrame(rows)
