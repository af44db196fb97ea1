"""benchmarks/report.py writes REPORT.md, its figures and README's speed numbers from results
files only; the scripts' agreement checks decide where a ratio is shown. Synthetic results, no
timing asserted."""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import report

META = {
    "date": "2026-12-03T06:00:00Z",
    "machine": {"platform": "Linux", "cpu_model": "Test CPU", "cores": 2},
    "load": {"start": [1.5, 1.0, 1.0], "end": [2.5, 1.0, 1.0]},
    "versions": {"python": "3.11"},
    "threads": {"requested": 1},
    "command": "python benchmarks/x.py",
}


def _write(results: Path, name: str, rows: list[dict]) -> None:
    (results / name).write_text(json.dumps({"metadata": META, "results": rows}))


def _pf_row(n: int, ft: float, ss: float, agree: bool) -> dict:
    libs = {"fusetrack": ft, "stonesoup": ss}
    return {
        "N": n, "sensors": 3, "clock": "wall",
        "seconds_per_step": libs, "rmse": {"fusetrack": 3.31, "stonesoup": 3.40},
        "wall_seconds_per_step": libs, "cpu_seconds_per_step": {k: 2 * v for k, v in libs.items()},
        "runs": {"fusetrack": 3, "stonesoup": 3},
        "agreement": {"stonesoup": {"difference": 0.09, "se": 0.01 if not agree else 0.05,
                                    "agree": agree}},
        "agree": agree,
        "speedup_over": {"stonesoup": {"wall": ss / ft, "cpu": ss / ft} if agree else None},
    }  # fmt: skip


def _peer_row(variant: str, ft: float, ss: float, agree: bool) -> dict:
    libs = {"fusetrack": ft, "stonesoup": ss}
    return {
        "variant": variant, "N": 1000, "peers": f"Stone Soup's {variant}", "ops_per_particle": 89.0,
        "runs": {"fusetrack": 5, "stonesoup": 5}, "rmse": {"fusetrack": 1.8, "stonesoup": 1.7},
        "rmse_se": {"fusetrack": 0.1, "stonesoup": 0.1}, "wall_seconds_per_step": libs,
        "cpu_seconds_per_step": libs, "ns_per_op": {k: v / 89e-6 for k, v in libs.items()},
        "agreement": {"stonesoup": {"difference": 0.1, "se": 0.14, "agree": agree}},
        "speedup_over": {"stonesoup": {"wall": ss / ft, "cpu": ss / ft} if agree else None},
        "agree": agree,
    }  # fmt: skip


def _synthetic(results: Path) -> None:
    _write(results, "pf_bearing.json",
           [_pf_row(1000, 0.001, 0.0123, True), _pf_row(100_000, 0.004, 0.0521, False)])  # fmt: skip
    _write(results, "batched_runs.json", [
        {"runs": r, "N": 1000, "seconds_per_step": {"separate": 0.001 * r, "batched": 0.0004 * r},
         "cpu_seconds_per_step": {"separate": 0.001 * r, "batched": 0.0005 * r},
         "speedup": 2.5, "cpu_speedup": 2.0, "bit_identical": True, "agree": True, "load": 1.0}
        for r in (1, 10)])  # fmt: skip
    diff = {"mean": 1e-13, "cov": 1e-14}
    _write(results, "kalman_batch.json", [
        {"N": 1000, "filter": "ekf", "seconds_per_step": {"fusetrack": 0.004, "filterpy": 0.2},
         "cpu_seconds_per_step": {"fusetrack": 0.004, "filterpy": 0.2}, "max_abs_diff": diff,
         "agree": True, "speedup": 50.0, "cpu_speedup": 50.0, "load": 1.0},
        {"N": 1000, "filter": "ukf", "seconds_per_step": {"fusetrack": 0.01, "filterpy": 1.0},
         "cpu_seconds_per_step": {"fusetrack": 0.01, "filterpy": 1.0},
         "max_abs_diff": {"mean": 1e-3, "cov": 0.0}, "agree": False, "speedup": None,
         "cpu_speedup": None, "load": 1.0}])  # fmt: skip
    _write(results, "multitarget.json", [
        {"tracker": "gnn", "targets": t, "clutter": 10.0, "seeds": 10, "scans": 100,
         "seconds_per_scan": {"fusetrack": 0.0001 * t, "stonesoup": 0.003 * t},
         "wall_seconds_per_scan": {"fusetrack": 0.0001 * t, "stonesoup": 0.0031 * t},
         "gospa": {"fusetrack": 17.79, "stonesoup": 17.79},
         "gospa_se": {"fusetrack": 0.12, "stonesoup": 0.12}, "agree": True, "speedup": 30.0,
         "wall_speedup": 31.0, "load": 1.0} for t in (10, 50)])  # fmt: skip
    _write(results, "zhai2007_speed.json", [
        {"N": n, "clock": "cpu", "seconds_per_step": {"bootstrap": 1e-4, "UPF": 1e-3},
         "cpu_seconds_per_step": {"bootstrap": 1e-4, "UPF": 1e-3},
         "wall_seconds_per_step": {"bootstrap": 2e-4, "UPF": 1e-3}} for n in (200, 1000)])  # fmt: skip
    _write(results, "filters.json", [
        {"variant": v, "family": "zhai2007", "baseline": "bootstrap", "N": 1000,
         "cpu_seconds_per_step": c * 1e-6, "wall_seconds_per_step": c * 1.5e-6,
         "cpu_ns_per_particle": c, "wall_ns_per_particle": 1.5 * c, "ops_per_particle": ops,
         "ns_per_op": c / ops, "ops_relative_to_baseline": ops / 89,
         "cpu_relative_to_baseline": c / 400, "wall_relative_to_baseline": c / 400}
        for v, c, ops in (("bootstrap", 400.0, 89.0), ("UPF", 4000.0, 928.0))
    ] + [{"skipped": [{"variant": "UPF", "N": 100000, "predicted_cpu_seconds": 900.0}]}])  # fmt: skip
    _write(results, "filter_peers.json", [
        _peer_row("bootstrap", 0.001, 0.0035, True), _peer_row("UPF", 0.008, 1.8, False),
        {"no_peer": {"Galerkin PF": "no library has a grid proposal"}, "particles": "a note",
         "skipped": [{"variant": "UPF", "library": "stonesoup", "N": 10000,
                      "estimated_seconds": 900.0}]}])  # fmt: skip
    _write(results, "pmmh.json", [
        {"library": lib, "T": 100, "N": 1000, "iterations": 300, "ms_per_iteration_wall": w,
         "ms_per_iteration_cpu": c, "acceptance_rate": 0.5, "posterior_mean_log_q": 0.2,
         "posterior_mean_log_r": -1.4, "mc_se_log_q": 0.1, "mc_se_log_r": 0.2,
         "agreement_with_limit_reference": {"agree": True}, "cpu_ratio_to_limit_reference": c / 3}
        for lib, w, c in (("fusetrack", 4.0, 3.0), ("particles", 40.0, 27.0),
                          ("limit_reference", 4.0, 3.0))])  # fmt: skip
    (results / "service_rate_1000.json").write_text(json.dumps({
        "nodes": 100, "rate_per_node": 10.0, "alignment": "closest", "faults": False,
        "duration_s": 60.0, "lost": 0, "tick_compute_ms_mean": 3.0, "node_cpu_ms_per_tick": 9.5,
        "accepted_per_s": 998.0, "node_cpu_share": 0.04, "generator_cpu_share": 0.05,
        "tick_latency_ms": {"p50": 6.0, "p99": 21.0, "max": 30.0},
        "memory_mb": {"first": 250.0, "last": 260.0, "max": 261.0}, "metadata": META}))  # fmt: skip


def test_report_is_generated_from_the_results_files(tmp_path: Path) -> None:
    results, out = tmp_path / "results", tmp_path / "out"
    results.mkdir()
    _synthetic(results)
    readme = tmp_path / "README.md"
    readme.write_text(
        f"# x\n\n## Speed\n\n{report.README_BEGIN}\nold\n{report.README_END}\n\ntail\n"
    )
    assert report.main(["--results", str(results), "--out", str(out), "--readme", str(readme)]) == 0
    text = (out / "REPORT.md").read_text()
    for fig in ("scaling_particles", "scaling_runs", "scaling_tracks", "scaling_targets",
                "scaling_filters", "scaling_zhai2007", "scaling_pmmh", "node_rate"):  # fmt: skip
        assert (out / f"{fig}.png").stat().st_size > 0
        assert f"({fig}.png)" in text
    # the numbers come from the files; N = 1e3 agrees: its ratios wall / cpu
    assert "| 1,000 | 1 ms / 2 ms | 12.3 ms / 24.6 ms | 12.3x / 12.3x |" in text
    # N = 1e5 disagrees: times shown, no ratio
    assert "| 100,000 | 4 ms / 8 ms | 52.1 ms / 104 ms | disagrees |" in text
    assert "| UKF | 1000 |" in text and "differ > 1e-9: none" in text
    assert "| EKF | 1000 | 4 ms / 4 ms | 200 ms / 200 ms | 50.0x / 50.0x |" in text
    assert "| 10 | 10 ms / 10 ms | 4 ms / 5 ms | 2.5x / 2.0x | True | 1.0 |" in text
    assert "| GNN | 50 | 10 | 5 ms (5 ms) | 150 ms (155 ms) | 30.0x / 31.0x |" in text
    assert "| UPF | 1 ms / 1 ms (10.0x / 5.0x) | 1 ms / 1 ms (10.0x / 5.0x) |" in text
    assert "100 x 10 = 1000 | closest | False | 60 | 998 | 0 | 6 / 21 / 30 ms | 3.0 | 9.5 | " \
           "0.04 / 0.05 |" in text  # fmt: skip
    # every variant against its baseline with its operations; the peers where the RMSE agrees
    assert "| zhai2007 | UPF | bootstrap | 4,000 / 6,000 ns; 10.0x base; 928 ops; 0.96x arith |" \
           in text  # fmt: skip
    assert "* skipped UPF at N = 100,000: predicted 900 CPU s" in text
    assert "| bootstrap | 1,000 | stonesoup | 1 ms / 1 ms | 3.5 ms / 3.5 ms | 3.5x / 3.5x |" in text
    assert (
        "| UPF | 1,000 | stonesoup | 8 ms / 8 ms | 1.8 s / 1.8 s | RMSE disagrees: none |" in text
    )
    assert "* Galerkin PF: no library has a grid proposal" in text
    assert "* stonesoup skipped on UPF at N = 10,000" in text
    assert "| particles | 100 | 1,000 | 300 | 27 ms / 40 ms | 9.0x | 0.50 |" in text
    assert "particles / fusetrack: 9.0x cpu, 10.0x wall." in text
    assert "load 1.5 -> 2.5" in text and "threads 1" in text and "Test CPU" in text
    assert "python benchmarks/pf_bearing.py" in text  # the commands that regenerate the files
    # README: the block between the markers is replaced, the rest kept
    new = readme.read_text()
    assert "old" not in new and new.endswith("\n\ntail\n")
    assert "N = 1,000 (default threads)" not in new  # the row nearest 1e5 is taken ...
    assert "N = 100,000 (default threads): fusetrack 4 ms per step, Stone Soup / fusetrack: " \
           "RMSE disagrees, no ratio" in new  # fmt: skip
    assert "EKF 50.0x wall / 50.0x cpu, UKF differs from FilterPy" in new
    assert "GNN 30.0x cpu / 31.0x wall" in new
    assert "live node, 1,000 readings/s offered: 100 x 10/s closest, 60 s: accepted 998/s, " \
           "tick p99 21 ms" in new  # fmt: skip
    assert "bootstrap stonesoup 3.5x cpu (N = 1,000), UPF stonesoup RMSE disagrees" in new
    assert "fusetrack at 1.00x the limit reference's CPU, particles / fusetrack 9.0x cpu" in new


def test_the_committed_report_is_what_the_committed_results_give(
    tmp_path: Path, monkeypatch
) -> None:
    """benchmarks/REPORT.md and README.md's speed numbers are regenerated whenever a results
    file changes (``python benchmarks/report.py``); the figures are not redrawn here."""
    monkeypatch.setattr(report, "plot", lambda path, panels: None)
    lines = report.report(report.HERE / "results", tmp_path)
    assert (report.HERE / "REPORT.md").read_text() == "\n".join(lines) + "\n"
    readme = (report.HERE.parent / "README.md").read_text()
    block = readme.split(report.README_BEGIN, 1)[1].split(report.README_END, 1)[0]
    assert block == "\n" + "\n".join(report.headline(report.HERE / "results")) + "\n"


def test_report_without_results_still_writes_the_regeneration_commands(tmp_path: Path) -> None:
    (tmp_path / "results").mkdir()
    report.main(["--results", str(tmp_path / "results"), "--out", str(tmp_path),
                 "--readme", str(tmp_path / "none.md")])  # fmt: skip
    text = (tmp_path / "REPORT.md").read_text()
    assert "## How to regenerate" in text and "--out benchmarks/results/pf_bearing.json" in text
    assert report.headline(tmp_path / "results")[0].startswith("* no results committed yet")


def test_the_newest_results_file_of_a_benchmark_is_reported(tmp_path: Path) -> None:
    _write(tmp_path, "kalman_batch.json", [{"N": 1}])  # META's date: 2026-12-03T06:00:00Z
    (tmp_path / "kalman_batch_later.jsonl").write_text(
        json.dumps({"N": 2, "date": "2026-12-03T07:00:00Z", "command": "python k.py"}) + "\n"
    )
    (tmp_path / "kalman_batch_undated.jsonl").write_text(json.dumps({"N": 3}) + "\n")
    name, doc = report.newest(tmp_path, "kalman_batch")  # type: ignore[misc]
    assert name == "kalman_batch_later.jsonl" and doc["results"][0]["N"] == 2
    assert doc["metadata"]["command"] == "python k.py"
    assert report.newest(tmp_path, "step_floor") is None
