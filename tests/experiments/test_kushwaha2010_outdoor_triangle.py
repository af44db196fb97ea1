"""kushwaha2010-outdoor-triangle (spec E6/H17): the 9.144 m triangle, source 2's placement, and the
trivial estimators beside the errors (issue 19)."""

import numpy as np
import pandas as pd

from fusetrack.cli import main
from fusetrack.experiments.kushwaha2010.outdoor_triangle import (
    NODES,
    _trivial_claims,
    second_position,
)


def test_triangle_is_15_ft_equilateral_and_source_2_at_the_separation():
    sides = [np.hypot(*(NODES[i] - NODES[(i + 1) % 3])) for i in range(3)]
    np.testing.assert_allclose(sides, 9.144)
    centroid = NODES.mean(axis=0)
    rng = np.random.default_rng(0)
    for sep in (0.5, 2.0, 8.0):
        p = second_position(sep, rng)
        assert abs(np.hypot(*(p - centroid)) - sep) < 1e-9
        assert np.min(np.hypot(*(NODES - p).T)) >= 1.0


def test_prior_mean_claims_fail_when_the_localiser_does_no_better():
    df = pd.DataFrame(
        {
            "separation": [0.5, 0.5, 8.0, 8.0],
            "error": [0.3, 0.32, 1.0, 3.0],
            "prior_mean_error": [0.25, 0.25, 4.0, 4.0],
        }
    )
    close, far = _trivial_claims(df)
    assert close.id.endswith("close") and not close.holds and close.kind == "diagnostic"
    assert far.id.endswith("far") and far.holds


def test_report_shows_the_trivial_estimators(tmp_path):
    """The quick run: the prior mean scores half the separation, and the report shows it beside
    the errors (issue 19)."""
    out = tmp_path / "ot"
    args = ["run", "kushwaha2010-outdoor-triangle", "--quick", "--runs", "1", "--no-progress"]
    assert main([*args, "--out", str(out)]) == 0
    df = pd.read_parquet(out / "results.parquet")
    np.testing.assert_allclose(df["prior_mean_error"], df["separation"] / 2, rtol=1e-12)
    report = (out / "report.md").read_text()
    assert "## The best possible: trivial estimators" in report
    assert "prior_mean_error" in report
