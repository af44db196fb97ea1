"""End to end: every Zhai 2007 experiment runs through the CLI (--quick --runs 1) and writes the
contract files with every claim of the spec it covers."""

import json

import pandas as pd
import pytest

from fusetrack.cli import main

EXPECTED = {
    "zhai2007-scalar": {"C1_order", "C1_improvement", "C2_time_ratio", "C3_smallest_variance"},
    "zhai2007-mcmc": {
        "C15_order_N100",
        "C15_order_N1000",
        "C15_PF-MH_beats_PF",
        "C15_pf_falls_with_n",
    },
    "zhai2007-multiple-model": {"C9_order", "C9_stationary", "C10_ccw_peak_sigma0.05", "C11_order"},
    "zhai2007-bearings": {"C4_order_E2", "C4_ekf_diverges", "C4_order_E3"},
    "zhai2007-galerkin": {"C12_beats_bs2000", "C12_variance", "C13_saturation", "E13_turn"},
    "zhai2007-discretisation": {
        "E15_along_bearing",
        "E16_order",
        "C14_S2A",
        "C14_S2B_turn",
        "A7_truth_and_z_outside_CV_inside_another",
        "A7_CA_fewest",
        "A7_CA_closest",
    },
    "zhai2007-sensor-network": {
        "C5_cpfsp_vs_bootstrap",
        "C6_threshold_78",
        "C7_loss",
        "C8_acceleration_change",
    },
}
BEYOND = {
    "zhai2007-scalar",
    "zhai2007-mcmc",
    "zhai2007-multiple-model",
    "zhai2007-bearings",
    "zhai2007-discretisation",
    "zhai2007-sensor-network",
}


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_experiment_quick_end_to_end(name, tmp_path):
    out = tmp_path / name
    args = [
        "run",
        name,
        "--quick",
        "--runs",
        "1",
        "--workers",
        "1",
        "--no-progress",
        "--out",
        str(out),
    ]
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["experiment"] == name
    ids = {c["id"] for c in summary["claims"]}
    assert EXPECTED[name] <= ids
    if name in BEYOND:  # issue 5's comparators: a summary entry beside the claims, a section
        winners = summary["beyond_the_paper"]["winners"]
        assert winners and all("winner at equal time" in w for w in winners.values())
        assert "## Beyond the paper" in (out / "report.md").read_text()
    for c in summary["claims"]:
        assert set(c) >= {"id", "statement", "paper", "ours", "tolerance", "holds"}
        assert isinstance(c["holds"], bool)
    df = pd.read_parquet(out / "results.parquet")
    assert len(df) > 0 and "method" in df.columns
    report = (out / "report.md").read_text()
    assert "Differences" in report and "paper" in report
    for line in report.splitlines():
        if line.startswith("![") and "](" in line:
            assert (out / line.split("](")[1].rstrip(")")).exists()
