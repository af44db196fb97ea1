"""Committed full-size reports match the code: experiments whose full-size run takes seconds are
rerun at the committed command's seed and runs, and every claim's ``ours`` must equal the
committed ``reports/NAME/summary.json`` (numbers to 1e-9 relative, text exactly; wall-clock and
floating-point-sensitive claims by presence, as in the golden fixture). A change to such an
experiment's code that moves a number fails here until its report is regenerated
(``fusetrack reproduce NAME --out reports/``)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fusetrack.cli import main

from .golden import claim_differences

REPORTS = Path(__file__).resolve().parents[2] / "reports"
PINNED = ("lee2009-robot-navigation", "nott2009-radio-accuracy")


@pytest.mark.parametrize("name", PINNED)
def test_full_size_claims_equal_the_committed_report(name, tmp_path):
    committed = json.loads((REPORTS / name / "summary.json").read_text())
    args = ["run", name, "--seed", str(committed["seed"]), "--runs", str(committed["runs"])]
    assert main([*args, "--workers", "1", "--no-progress", "-q", "--out", str(tmp_path)]) == 0
    rerun = json.loads((tmp_path / "summary.json").read_text())
    ours = {c["id"]: c["ours"] for c in rerun["claims"]}
    expected = {c["id"]: c["ours"] for c in committed["claims"]}
    assert claim_differences(name, expected, ours) == []
