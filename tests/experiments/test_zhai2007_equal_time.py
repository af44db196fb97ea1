"""EqualTime: calibrates both comparators per configuration key and reports what it calibrated."""

from __future__ import annotations

from typing import Any

import pandas as pd
import pytest

from fusetrack.experiments.zhai2007 import equal_time
from fusetrack.experiments.zhai2007.equal_time import EQUAL_TIME_METHODS, EqualTime


def test_calibrate_records_counts_and_target_per_key(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[tuple[Any, tuple[str, ...], int]] = []

    def fake(scn: Any, reference: Any, methods: tuple[str, ...], *, repeats: int) -> Any:
        calls.append((scn, methods, repeats))
        return {m: 100 * len(calls) for m in methods}, 0.5 * len(calls)

    monkeypatch.setattr(equal_time, "equal_time_particles", fake)
    eq = EqualTime(repeats=2)
    assert eq.calibrate("A", "scn-a", lambda: None) == {"UPF": 100, "bootstrap equal time": 100}
    eq.calibrate(7, "scn-b", lambda: None)
    assert calls == [("scn-a", EQUAL_TIME_METHODS, 2), ("scn-b", EQUAL_TIME_METHODS, 2)]
    assert eq.n_particles == {
        "A": dict.fromkeys(EQUAL_TIME_METHODS, 100),
        7: dict.fromkeys(EQUAL_TIME_METHODS, 200),
    }
    assert eq.target == {"A": 0.5, 7: 1.0}


def test_compare_reports_the_calibration(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: dict[str, Any] = {}

    def fake_compare(per_run: Any, reference: Any, path: Any, **kw: Any) -> str:
        seen.update(kw)
        return "comparison"

    monkeypatch.setattr(equal_time, "compare", fake_compare)
    eq = EqualTime(repeats=1, n_particles={"A": {"UPF": 30}}, target={"A": 2.0})
    assert (
        eq.compare(pd.DataFrame(), "ref", None, notes=["n"], calibration=" more.") == "comparison"
    )
    assert (
        seen["calibration"].endswith(" more.")
        and "A: target 2 s -> UPF N = 30" in seen["calibration"]
    )
    assert seen["n_particles"] == {"A": {"UPF": 30}} and seen["notes"] == ["n"]
    eq.compare(pd.DataFrame(), "ref", None, notes=[], n_particles={"UPF": 30})
    assert seen["n_particles"] == {"UPF": 30}


def test_compare_runs_scores_each_run(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: dict[str, Any] = {}

    def fake_compare(per_run: pd.DataFrame, reference: Any, path: Any, **kw: Any) -> str:
        seen.update(kw, per_run=per_run, path=path)
        return "comparison"

    class Ctx:
        def figure_path(self, name: str) -> str:
            return f"figs/{name}.png"

    monkeypatch.setattr(equal_time, "compare", fake_compare)
    rows = pd.DataFrame(
        {"cfg": "A", "method": "m", "run": [0, 0, 1, 1], "sq": [1.0, 3.0, 4.0, 4.0], "seconds": 2.0}
    )
    eq = EqualTime(repeats=1)
    eq.compare_runs(Ctx(), rows, ["cfg"], "sq", "m", notes=[])  # type: ignore[arg-type]
    assert seen["path"] == "figs/error_vs_seconds.png" and seen["by"] == ["cfg"]
    assert seen["per_run"]["error"].tolist() == pytest.approx([2**0.5, 2.0])
