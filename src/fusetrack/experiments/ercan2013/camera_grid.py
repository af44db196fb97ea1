"""E1's grid (Ercan et al. 2013, Sec. 6.1, Figs. 5-6) and the C3 claims read off it, shared by
``ercan2013-cameras`` (the paper's tracker) and ``ercan2013-cameras-sigma-v`` (the same grid with
trackers that assume more motion noise).

Square 100 x 100 room with one static occluder, M = 40 moving occluders, the first k cameras of
the fixed list {1, 7, 5, 3, 2, 4, 6, 8}, three occluder-prior levels: perfect (RMSE_occ = 0),
Gaussian priors from Kalman filters (RMSE_occ ~ 6.67) and none (RMSE_occ = RMSE_max). C3: mean
RMSE_tr falls with k for every level, and perfect <= Gaussian <= none at every k.
"""

from __future__ import annotations

from typing import Any

import pandas as pd

from ...evaluation import Claim, ClaimKinds
from .common import mean_std

SIGMA_PSI = (
    17.0  # calibrated so the random-walk Kalman priors have RMSE_occ ~ 6.67 (paper: sigma_psi = 8)
)
PRIORS = {
    "perfect": "RMSE_occ = 0",
    "gaussian": "RMSE_occ ~ 6.67 (Gaussian priors)",
    "none": "RMSE_occ = RMSE_max",
}
"""The paper's three prior levels and the curve each is in Fig. 6."""


def camera_counts(quick: bool) -> list[int]:
    """Fig. 6's camera counts: 1..8 (the paper's x-axis), a quick run's 2, 4, 8."""
    return [2, 4, 8] if quick else list(range(1, 9))


def grid_configs(quick: bool, size: dict[str, int]) -> list[dict[str, Any]]:
    """The paper's prior x camera-count grid (label "corrected": the floored likelihood)."""
    return [
        {
            "scene": "square",
            "n_occluders": 40,
            "prior": p,
            "sigma_psi": SIGMA_PSI,
            "k": k,
            "method": "fixed",
            "label": "corrected",
            **size,
        }
        for p in PRIORS
        for k in camera_counts(quick)
    ]


def mean_pivot(df: pd.DataFrame) -> pd.DataFrame:
    """Mean RMSE_tr per camera count (rows) and prior level (columns) of one grid's runs."""
    return mean_std(df, ["prior", "k"]).pivot(index="k", columns="prior", values="mean")


def spearman(pivot: pd.DataFrame, prior: str) -> float:
    """Spearman rho of camera count against mean RMSE_tr of one prior level."""
    return float(
        pd.Series(pivot.index.to_numpy(float)).corr(
            pd.Series(pivot[prior].to_numpy()), method="spearman"
        )
    )


def ordered_share(pivot: pd.DataFrame) -> float:
    """Share of camera counts with perfect <= Gaussian <= none (mean RMSE_tr)."""
    ordered = (pivot["perfect"] <= pivot["gaussian"]) & (pivot["gaussian"] <= pivot["none"])
    return float(ordered.mean())


def need_share(quick: bool) -> float:
    """C3_ordering's bar: the share of camera counts in the paper's order."""
    return 0.6 if quick else 0.75


def need_rho(quick: bool) -> float:
    """C3_decreasing's bar: Spearman rho of k against mean RMSE_tr at most this."""
    return -0.5 if quick else -0.7


def ordering_claim(
    kinds: ClaimKinds, claim_id: str, statement: str, share: float, quick: bool
) -> Claim:
    """C3's ordering: ``share`` of camera counts in the paper's order reaches the bar."""
    need = need_share(quick)
    return kinds.claim(claim_id, statement, "all camera counts", share, f">= {need}", share >= need)


def decreasing_claim(
    kinds: ClaimKinds, claim_id: str, statement: str, pivot: pd.DataFrame, prior: str, quick: bool
) -> Claim:
    """C3's trend: mean RMSE_tr of ``prior`` falls as cameras are added (Spearman rho)."""
    rho, need = spearman(pivot, prior), need_rho(quick)
    return kinds.claim(claim_id, statement, "decreasing", rho, f"rho <= {need}", rho <= need)
