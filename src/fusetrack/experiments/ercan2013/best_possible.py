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

from ...evaluation import Claim, ClaimKinds, agreement_claim, mean_with_se

BEST_PREFIX = "best L="
"""Label prefix of a posterior-mean run: ``best L=5000|0`` (the sweep point labelled "0")."""
FACTORS = {"full": (2, 5), "quick": (1, 2)}
"""Particle counts of the two posterior-mean series, as multiples of the run's L (a multiple
of 1 reuses the sweep's own runs)."""
TRIVIAL = "room centre (trivial, RMSE_max)"


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
