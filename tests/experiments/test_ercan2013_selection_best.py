"""E6's best possible (issue 19 item 3): all cameras with perfect priors as a floor under every
selection method of Fig. 12 (hand-made run tables, no simulation)."""

import re

import pandas as pd
import pytest

from fusetrack.experiments.ercan2013 import best_possible as bp
from fusetrack.experiments.ercan2013 import selection, selection_best


def _best_runs(l_values: list[float], l2_values: list[float]) -> pd.DataFrame:
    rows = [
        {"particles": n, "run": r, "rmse_tr": v, "label": f"best L={n}|all-perfect"}
        for n, values in ((100, l_values), (200, l2_values))
        for r, v in enumerate(values)
    ]
    return pd.DataFrame(rows)


def _floor(l_values, l2_values) -> bp.BestPossible:
    runs = pd.DataFrame({"run": [0, 1, 0, 1], "rmse_max": [40.0, 40.0, 40.0, 40.0]})
    return selection_best.estimate(runs, _best_runs(l_values, l2_values), (100, 200), 100)


def _table(greedy_k2: float) -> pd.DataFrame:
    return pd.DataFrame(
        {
            "label": ["greedy-perspective", "greedy-perspective", "fixed"],
            "k": [2, 6, 2],
            "mean": [greedy_k2, 2.0, 9.0],
            "std": [0.2, 0.2, 1.0],
        }
    )


def test_the_floor_series_is_the_all_camera_run_with_perfect_priors_at_both_counts():
    all_config = {"method": "all", "k": 1, "label": "all", "prior": "gaussian", "metric_gap": False}
    configs = selection_best.best_configs(all_config, (100, 200))
    assert [(c["particles"], c["prior"], c["method"]) for c in configs] == [
        (100, "perfect", "all"),
        (200, "perfect", "all"),
    ]
    assert bp.is_best(
        pd.DataFrame({"label": [c["label"] for c in configs] + ["all"]})
    ).tolist() == [
        True,
        True,
        False,
    ]


def test_no_method_below_a_converged_floor_holds():
    best = _floor([1.0, 1.2], [1.05, 1.15])
    assert best.best("all-perfect") == pytest.approx((1.1, 0.05))
    assert best.trivial == (40.0, 0.0)
    claims = {
        c.id: c
        for c in selection_best.claims(
            selection.CLAIM_KINDS, best, selection_best.method_means(_table(3.0), 10)
        )
    }
    assert claims["BP_no_method_below_floor"].holds
    assert claims["BP_converged_all_perfect"].holds
    assert {c.kind for c in claims.values()} == {"diagnostic"}


def test_a_method_below_the_floor_and_an_unconverged_floor_fail():
    best = _floor([3.0, 3.2], [2.9, 3.1])  # floor 3.0: greedy k = 6 at 2.0 +- 0.06 is below it
    means = selection_best.method_means(_table(3.5), 10)
    claims = {c.id: c for c in selection_best.claims(selection.CLAIM_KINDS, best, means)}
    below = claims["BP_no_method_below_floor"]
    assert not below.holds and "greedy-perspective k=6" in str(below.ours)
    far = _floor([1.0, 1.1], [3.0, 3.1])
    assert not {c.id: c for c in selection_best.claims(selection.CLAIM_KINDS, far, means)}[
        "BP_converged_all_perfect"
    ].holds


def test_section_lays_out_the_floor_and_each_methods_ratio():
    best = _floor([1.0, 1.2], [1.0, 1.2])
    text = selection_best.section(best, selection_best.method_means(_table(3.3), 10), 12, 2)
    assert "all 12 cameras, perfect priors (L = 200) | 1.1 ± 0.1" in text
    assert re.search(r"\|\s+2 \|\s+8\.18 \|\s+3\s+\|", text)  # greedy k = 2: 3.3 / 1.1 = 3
    assert "room centre" in text
