"""Compare an experiment's ``--quick`` claims with the golden fixture (``quick_claims.json``).

The fixture was recorded before the "one tracking model" reshaping (issue 16) by ``record.py``;
a reshaping must leave every claim's ``ours`` value where it was: numbers to 1e-9 (relative),
text exactly.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

FIXTURE = Path(__file__).with_name("quick_claims.json")
RTOL = 1e-9

# Claims that measure wall-clock time: two recordings of the same code (before the reshaping)
# gave different values for exactly these, so they are compared by presence only.
TIMING = {
    "ercan2013-likelihood-cost": {
        "C7_close_to_linear",
        "C7_far_below_exponential",
        "C7_tracks_no_prior",
    },
    "ercan2013-selection": {"C9_greedy_cheaper"},
    "kushwaha2010-beamformer": {"faster_than_realtime"},
    "kushwaha2010-sbe": {"fusion_step_realtime"},
    "nott2009-video": {"speed-ekf-1000", "speed-front-end"},
    "zhai2007-scalar": {"C2_cheaper_than_bs2000", "C2_time_ratio"},
}

# Claims that depend on the last bits of the CPU's floating-point results (NumPy's SIMD exp/log,
# BLAS): a Markov chain's accept/reject (MCMCDA), the EKF-bank proposal's chaotic scalar model,
# a greedy/brute-force camera choice between near-equal costs. The code of the recording commit
# (dd356c0) gives other values for exactly these on a second machine (checked 2026-12-03), so no
# reshaping can be held to them across machines: they are compared by presence only, and
# ``record.py --check`` prints their differences as notes.
FLOATING_POINT = {
    "ercan2013-lab": {"C11_fig15_greedy_brute"},
    "kushwaha2010-crossing": {  # the bound's claims: over the MCMCDA tracks' ticks
        "per_track_errors",
        "BP_crossing_above_bound",
        *(f"BP_fig26_track_{i}_possible" for i in (1, 2, 3)),
    },
    "kushwaha2010-mcmcda": {
        "av_lowest_error",
        "product_lower_error",
        "mcmcda_beats_sbe",
        "BP_mcmcda_above_bound",  # the bound's claims: over the MCMCDA tracks' ticks
        *(f"BP_table8_{k}_possible" for k in ("sum", "product", "A", "V", "AV")),
    },
    "zhai2007-visual": {"E18-1_beats_baseline", "E18-1_keeps_lock"},  # a lost track's RMSE
    # the best possible's posterior mean of one quick run on a bimodal model (2.31 -> 2.23 and
    # 3.88 -> 3.89 on an AMD znver4 with AVX-512, 2026-12-04)
    "zhai2007-mcmc": {"BP_possible_table15"},
    "zhai2007-scalar": {
        "BP_variant_z=x^2/20",
        "C1_order",
        "C1_order_variant_printed",
        "C1_order_variant_z=x^2",
        "C1_order_variant_z=x^2/20",
        "C1_order_variant_sigma_v^2=100",
        "C1_level_PF-SP-PEKF",
        "C1_improvement",
    },
}


def presence_only(name: str) -> set[str]:
    """The claims of experiment ``name`` compared by presence only (timing, floating point)."""
    return TIMING.get(name, set()) | FLOATING_POINT.get(name, set())


def floating_point_notes(name: str, expected: dict[str, Any], got: dict[str, Any]) -> list[str]:
    """Differences in the floating-point-sensitive claims (informative, never a failure)."""
    keys = FLOATING_POINT.get(name, set()) & expected.keys() & got.keys()
    return differences({k: expected[k] for k in keys}, {k: got[k] for k in keys}, name)


def load() -> dict[str, dict[str, Any]]:
    return json.loads(FIXTURE.read_text())


def claim_differences(name: str, expected: dict[str, Any], got: dict[str, Any]) -> list[str]:
    """Where experiment ``name``'s claims ``got`` differ from the golden ``expected`` (timing
    and floating-point-sensitive claims: only that they are there)."""
    timing = presence_only(name)
    keep = {k: v for k, v in expected.items() if k not in timing}
    seen = {k: v for k, v in got.items() if k not in timing}
    missing = sorted(timing & expected.keys() - got.keys())
    return [f"{name}: claims {missing} missing"] * bool(missing) + differences(keep, seen, name)


def differences(expected: Any, got: Any, where: str = "") -> list[str]:
    """Every place where ``got`` differs from ``expected`` (empty when they agree)."""
    if isinstance(expected, bool) or isinstance(got, bool):
        return [] if expected == got else [f"{where}: {got!r} != golden {expected!r}"]
    if isinstance(expected, int | float) and isinstance(got, int | float):
        if math.isnan(expected) and math.isnan(got):
            return []
        if math.isclose(expected, got, rel_tol=RTOL, abs_tol=1e-12):
            return []
        return [f"{where}: {got!r} != golden {expected!r}"]
    if isinstance(expected, dict) and isinstance(got, dict):
        out = (
            [f"{where}: keys {sorted(set(got) ^ set(expected))} differ"]
            if set(got) != set(expected)
            else []
        )
        for k in expected.keys() & got.keys():
            out += differences(expected[k], got[k], f"{where}.{k}")
        return out
    if isinstance(expected, list) and isinstance(got, list) and len(expected) == len(got):
        out: list[str] = []
        for i, (e, g) in enumerate(zip(expected, got, strict=True)):
            out += differences(e, g, f"{where}[{i}]")
        return out
    return [] if expected == got else [f"{where}: {got!r} != golden {expected!r}"]
