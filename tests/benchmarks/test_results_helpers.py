"""benchmarks/_results.py: the agreement rule, thread limits, metadata and the results file.

No timings are asserted (speed is measured by the benchmarks, not by the tests).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import _results


def test_mean_se_hand_computed() -> None:
    m, se = _results.mean_se([1.0, 2.0, 3.0, 6.0])
    assert m == 3.0
    # sample variance (4 + 1 + 0 + 9) / 3 = 14 / 3; SE = sqrt(14 / 3 / 4)
    assert se == pytest.approx(math.sqrt(14 / 12), rel=1e-12)
    assert _results.mean_se([2.5]) == (2.5, None)


def test_monte_carlo_agreement_is_three_combined_standard_errors() -> None:
    # combined SE sqrt(0.3^2 + 0.4^2) = 0.5: agree up to |difference| 1.5
    inside = _results.agree_monte_carlo(10.0, 0.3, 11.49, 0.4)
    outside = _results.agree_monte_carlo(10.0, 0.3, 11.51, 0.4)
    assert inside["agree"] is True and outside["agree"] is False
    assert inside["se"] == pytest.approx(0.5) and inside["difference"] == pytest.approx(-1.49)
    # a missing SE borrows the other's; both missing: not checked
    borrowed = _results.agree_monte_carlo(10.0, None, 10.5, 0.1)
    assert borrowed["se"] == pytest.approx(0.1 * math.sqrt(2)) and borrowed["agree"] is False
    assert _results.agree_monte_carlo(1.0, None, 1.0, None)["agree"] is None
    assert _results.agree_monte_carlo(float("nan"), 0.1, 1.0, 0.1)["agree"] is None


def test_few_runs_widen_the_factor_to_the_t_quantile() -> None:
    from scipy.stats import norm, t

    # equal SEs from 3 runs each: Welch-Satterthwaite dof = (2v)^2 / (2 v^2 / 2) = 4
    q = _results.t_factor(0.1, 0.1, 3, 3)
    assert q == pytest.approx(t.ppf(1 - 0.0027 / 2, 4), rel=1e-12)
    assert 6.0 < q < 7.0
    # the level is the normal's 3 sigma: many runs give back 3
    assert 2 * norm.sf(3.0) == pytest.approx(_results.SE_LEVEL, rel=0.01)
    assert _results.t_factor(0.1, 0.1, 10**6, 10**6) == pytest.approx(3.0, abs=0.01)
    # combined SE 0.1 * sqrt(2): 0.8 apart is 5.7 SE, under q = 6.4 with 3 runs each
    assert _results.agree_monte_carlo(1.0, 0.1, 1.8, 0.1, 3, 3)["agree"] is True
    assert _results.agree_monte_carlo(1.0, 0.1, 1.8, 0.1)["agree"] is False
    assert _results.agree_monte_carlo(1.0, 0.1, 1.8, 0.1, 50, 50)["agree"] is False


def test_exact_agreement_and_combination() -> None:
    assert _results.agree_exact(1e-10) and not _results.agree_exact(2e-9)
    assert not _results.agree_exact(float("nan"))
    assert _results.all_agree([True, None, False]) is False
    assert _results.all_agree([True, None]) is True
    assert _results.all_agree([None]) is None


def test_ratio_refuses_missing_values() -> None:
    assert _results.ratio(6.0, 2.0) == 3.0
    assert _results.ratio(None, 2.0) is None and _results.ratio(1.0, 0.0) is None


def test_limit_threads_sets_blas_and_numba_and_restores_them() -> None:
    import numba
    import numpy as np  # noqa: F401 - loads the BLAS that threadpoolctl limits
    from threadpoolctl import threadpool_info

    before = numba.get_num_threads()
    with _results.limit_threads(1) as setting:
        assert numba.get_num_threads() == 1
        assert all(p["num_threads"] == 1 for p in threadpool_info() if p["user_api"] == "blas")
        assert setting["requested"] == 1 and setting["numba"] == 1
    assert numba.get_num_threads() == before
    with _results.limit_threads(None) as setting:  # default: BLAS one thread, Numba untouched
        assert setting["requested"] is None
        assert numba.get_num_threads() == before
        assert all(p["num_threads"] == 1 for p in threadpool_info() if p["user_api"] == "blas")
    with pytest.raises(ValueError, match="--threads"):
        with _results.limit_threads(0):
            pass


def test_arguments_and_output_path(tmp_path: Path) -> None:
    ap = argparse.ArgumentParser()
    _results.add_arguments(ap)
    assert _results.out_path(ap.parse_args([]), "x.py") is None
    assert _results.out_path(ap.parse_args(["--save"]), "/a/b/pf_bearing.py") == (
        _results.RESULTS / "pf_bearing.json"
    )
    args = ap.parse_args(["--out", str(tmp_path / "r.json"), "--threads", "2"])
    assert _results.out_path(args, "x.py") == tmp_path / "r.json" and args.threads == 2


def test_run_saves_metadata_and_results(tmp_path: Path) -> None:
    import numpy  # noqa: F401 - imported, so its version is recorded

    run = _results.Run(["--N", "10"], script=str(_results.HERE / "pf_bearing.py"))
    run.threads = {"requested": 1}
    path = run.save(tmp_path / "sub" / "r.json", [{"N": 10, "t": 0.5}])
    doc = json.loads(path.read_text())  # type: ignore[union-attr]
    meta = doc["metadata"]
    assert doc["results"] == [{"N": 10, "t": 0.5}]
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", meta["date"])
    assert meta["command"] == "python benchmarks/pf_bearing.py --N 10"
    assert {"platform", "cpu_model", "cores"} <= set(meta["machine"])
    assert len(meta["load"]["start"]) == 3 and len(meta["load"]["end"]) == 3
    assert "numpy" in meta["versions"] and "python" in meta["versions"]
    assert meta["threads"] == {"requested": 1}
    assert _results.load(path) == doc
    assert run.save(None, []) is None


def test_load_reads_json_lines_and_service_documents(tmp_path: Path) -> None:
    lines = tmp_path / "m.jsonl"
    lines.write_text('{"a": 1}\n\n{"a": 2}\n')
    assert _results.load(lines) == {
        "metadata": {"source": "m.jsonl"},
        "results": [{"a": 1}, {"a": 2}],
    }
    svc = tmp_path / "service_x.json"
    svc.write_text(json.dumps({"nodes": 3, "metadata": {"date": "D"}}))
    doc = _results.load(svc)
    assert doc["results"] == [{"nodes": 3}] and doc["metadata"]["date"] == "D"
    plain = tmp_path / "old.json"
    plain.write_text('{"N=200": {}}')
    assert _results.load(plain)["results"] == [{"N=200": {}}]
