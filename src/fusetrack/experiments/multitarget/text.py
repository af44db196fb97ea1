"""The report body of ``multitarget-bearings``."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from ...evaluation import Claim
from .claims import mean_se
from .scenario import ARRAYS_USED

if TYPE_CHECKING:
    from .experiment import Options


def hypotheses_verdict(claims: Sequence[Claim]) -> str:
    """``"k of n hypotheses hold (ids); these do not: ids."`` (beyond-the-paper experiments)."""
    held = [c.id for c in claims if c.holds]
    failed = [c.id for c in claims if not c.holds]
    return (
        f"{len(held)} of {len(claims)} hypotheses hold"
        + (f" ({', '.join(held)})" if held else "")
        + (f"; these do not: {', '.join(failed)}." if failed else ".")
    )


def _candidate_lines(df: pd.DataFrame) -> str:
    lines = []
    for n in (2, 3):
        t, _ = mean_se(df, n, "JPDA", "true_candidates")
        g, _ = mean_se(df, n, "JPDA", "ghost_candidates")
        lines.append(f"* {n} arrays: {t:.1f} candidates near a target and {g:.1f} ghosts per scan")
    return "\n".join(lines)


def _methods_text(n_mc: int) -> str:
    """How each method is built (the report's "Methods" list)."""
    return f"""Methods, all on the same scans:

* **GNN / JPDA**: every pair of bearings of two arrays intersected (rays crossing at more than
  5°, in front of both arrays, in the field); each point a position measurement of "its" pair
  of arrays (one sensor per pair: a target gives at most one point per pair) with covariance
  `(HᵀR⁻¹H)⁻¹`, `H` the Jacobian of the two bearings at the point (`[-d_y, d_x]/r²` per array),
  `R = σ² I` — the linearised inverse of the two bearings, checked against Monte Carlo in
  `tests/experiments/test_multitarget_bearings.py`. `MultiTargetTracker` (Kalman, nearly
  constant velocity q = 0.5 m²/s³) with `GlobalNearestNeighbour` or
  `JointProbabilisticDataAssociation`; P_D per pair = P_D²; clutter density per pair = its mean
  number of points per scan / field area (every point counted as clutter: an upper bound the
  tracker could measure itself); 3-of-4 confirmation, deletion after 4 misses in a row or
  existence probability < 0.1.
* **MCMCDA**: `association.MCMCDA` as `kushwaha2010-mcmcda` runs it, on the candidates of all
  pairs pooled per scan, {n_mc} iterations per scan, window 12 scans; each candidate's
  observation noise is its own triangulation covariance (in the gate, the track score and a
  new track's prior; earlier versions used one isotropic σ, the median candidate σ), its
  false-alarm rate the mean number of candidates
  per scan minus the number of targets. Its tracks are the committed ones (an observation's
  track is fixed when it leaves the window: a 3-s fixed-lag decision), the others' are filtered
  online.
* **grid+JPDA**: each array's bearings as a cell likelihood `1 - P_D + P_D/κ Σ_j N(z_j; θ(x), σ²)`
  averaged over the cell's arc (Kushwaha 2010, Eq. 32), fused by product (Eq. 30) without a
  temporal prior, peaks as in `kushwaha2010-mcmcda` (`association.likelihood_peaks`), fed to
  the JPDA tracker with the peak's covariance = inverse Fisher information of all arrays +
  cell²/12.
* **direct**: the JPDA tracker on the bearings themselves (EKF, one `sensors.Bearing` per array,
  clutter density = clutter/2π per rad); candidate points only start tracks (a birth-only sensor:
  points inside a track's gate are neither used nor start tracks), so no track is ever updated
  with a triangulated point."""


def _metrics_text(opts: Options) -> str:
    return f"""Metrics per run: GOSPA (c = {opts.gospa_c:g} m, p = 2, α = 2) averaged over scans as
`mean_t d_t²` components (localisation / missed / false, m²) and its root (`gospa`, m);
OSPA⁽²⁾ over the whole run (c = {opts.gospa_c:g} m, p = 1); CLEAR MOT at {opts.mot_threshold:g}
m (identity switches, MOTA); ghost tracks = confirmed tracks whose median distance to the
nearest target exceeds {opts.mot_threshold:g} m. Mean ± standard error over runs."""


def report_text(
    df: pd.DataFrame,
    table: pd.DataFrame,
    claims: Sequence[Claim],
    figs: Sequence[Path],
    runs: int,
    duration: float,
    n_mc: int,
    opts: Options,
    best: str,
) -> str:
    """Set-up, verdict (of the hypotheses ``claims``), the mean ± SE table, figures, the best
    possible section ``best`` and what the numbers say."""
    arrays = ", ".join(ARRAYS_USED)
    return f"""
Beyond the papers (fusetrack issue 17): several targets tracked from *unlabelled* bearings of
two or three arrays, where every pair of bearings of two arrays intersects and most
intersections are ghosts. Verdict: {hypotheses_verdict(claims)}

## Set-up

{runs} runs per configuration; each run: {opts.targets} targets on straight crossing paths at
2-3.5 m/s (alternately eastwards and westwards, random heights, most pairs cross) in Kushwaha
2010's 35 m x 20 m field for {duration:g} s at 4 Hz; arrays at Kushwaha's acoustic nodes
{arrays} (the first two, or all three). Every scan each array reports its targets' bearings
with P_D = {opts.p_detect:g}, σ = {opts.sigma_deg:g}°, bearings within 2° merged, plus
Poisson({opts.clutter:g}) clutter bearings uniform on the circle, shuffled.

{_methods_text(n_mc)}

{_metrics_text(opts)}

Candidates per scan (a candidate within {opts.mot_threshold:g} m of a target counts as true):

{_candidate_lines(df)}

## Results (mean ± SE over {runs} runs)

{table.to_markdown()}

![one run, 2 arrays]({figs[0].name})

![one run, 3 arrays]({figs[1].name})

![GOSPA over time]({figs[2].name})

{best}
## Reading

* Each claim above is a hypothesis stated before the run; those marked **no** failed on these
  runs and are reported as measured.
* Ghosts of one pair of arrays are consistent from scan to scan (two bearings moving smoothly
  make an intersection moving smoothly), so a position tracker confirms them like targets; only
  a third array tells them apart, and only a method that weighs the third array's bearings
  against the same point (the grid product, the direct bearing tracker) uses that. The
  per-pair position trackers see each pair's ghosts as detections of that pair and keep them
  as long as that pair keeps reporting them.
* MCMCDA sees up to one point per pair for every target and treats the extra ones as false
  alarms (one observation per target per scan is its model).
* Limits: straight paths, a constant detection probability, clutter uniform on the circle,
  bearings merged only within 2°, no array position or clock errors.
"""
