"""Smoke test of benchmarks/filters.py: one variant per family runs at a tiny size, its row
carries the operation count and the ratio to its baseline, and the results file is written."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import filters

ONE_PER_FAMILY = ["PF-SP-PEKF", "UPF", "ASIR, occlusion-aware", "detection-function PF"]


def test_one_variant_per_family_runs(capsys, tmp_path):
    out = tmp_path / "filters.json"
    argv = ["--N", "100", "--steps", "2", "--repeats", "1", "--json", "--out", str(out)]
    assert filters.main([*argv, "--variants", *ONE_PER_FAMILY]) == 0
    rows = json.loads(capsys.readouterr().out)
    timed = {r["variant"]: r for r in rows if "variant" in r}
    baselines = {"bootstrap", "ASIR, position fix", "bootstrap, 9 Gaussian bearings"}
    assert set(timed) == set(ONE_PER_FAMILY) | baselines  # each variant and its baseline
    for name in ONE_PER_FAMILY:
        r = timed[name]
        assert r["N"] == 100 and r["cpu_seconds_per_step"] > 0
        assert r["ops_per_particle"] == filters.operations(name, 100)
        assert r["cpu_relative_to_baseline"] is not None
    for name in baselines:
        assert timed[name]["ops_relative_to_baseline"] == 1.0
    doc = json.loads(out.read_text())
    assert doc["metadata"]["command"].startswith("python benchmarks/filters.py")
    assert doc["results"][-1]["skipped"] == []
    assert all(r["above_arithmetic"] is not None for r in rows if "variant" in r)
    table = filters.markdown(doc).splitlines()
    assert len(table) == 2 + len(timed) and "| kushwaha2010 | detection-function PF |" in table[-1]


def test_operation_counts_follow_the_algorithms():
    # the bank is shared: its per-particle share falls as 1/N; the grid ancestor sum grows as N
    assert filters.operations("PF-SP-PEKF", 1000) > filters.operations("PF-SP-PEKF", 100000)
    assert filters.operations("PF-SP-PEKF", 10**9) - filters.OPS["PF-SP-PEKF"][0] < 1e-3
    g1, g2 = filters.operations("Galerkin PF", 1000), filters.operations("Galerkin PF", 2000)
    assert abs((g2 - g1) - filters.PAIR * 1000) < filters.GALERKIN_STEP / 1000
    assert set(filters.OPS) == set(filters.cases())


def test_sizes_over_the_budget_are_skipped():
    # a quadratic variant measured at N = 100 predicts 10^4 times the cost at N = 10^4
    assert filters.predicted_cpu("Galerkin PF", (100, 0.5), 10000, 2) == 0.5 * 1e4 * 2
    assert filters.predicted_cpu("bootstrap", (100, 0.5), 10000, 2) == 0.5 * 100 * 2
    assert filters.predicted_cpu("bootstrap", None, 10**6, 2) == 0.0
