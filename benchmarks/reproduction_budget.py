"""Where a full-size reproduction's CPU goes, and what the 30-minute budget asks of each part.

Reads the committed ``reports/*/results.parquet`` (no run): every report whose runs record their
CPU seconds and their likelihood clock (``cpu_seconds``, ``likelihood_ms_per_step`` and ``steps``:
the Ercan et al. 2013 trackers) is split into

* the likelihood (Eqs. 6-9: ``likelihood_ms_per_step x steps``),
* the camera-selection epochs (``selection_ms_per_epoch x ceil(steps / period)``), and
* everything else (prediction, resampling, the world simulation, the per-step Python).

Against the budget (:data:`fusetrack.tools.report_tally.RUN_BUDGET_SECONDS` of wall time with the
report's workers) it prints the overall speed-up the run needs, the wall time if the likelihood
cost nothing (``wall - likelihood / workers``: everything else stays, the untimed world
simulation, the report and idle workers included) and the speed-up of the likelihood alone that
would meet the budget so (``never``: not even a free likelihood). The parallel efficiency is the
timed CPU over ``workers x wall``. These are our diagnostic of the committed timings, not
measurements: a rerun on a faster or slower hour of this shared machine moves them.

    python benchmarks/reproduction_budget.py [--reports reports] [--json] [--save]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from fusetrack.tools.report_tally import RUN_BUDGET_SECONDS

COLUMNS = ("cpu_seconds", "likelihood_ms_per_step", "steps")


def split(folder: Path) -> dict[str, Any] | None:
    """The CPU split of one report folder, or ``None`` if its runs do not record it."""
    parquet, summary = folder / "results.parquet", folder / "summary.json"
    if not (parquet.is_file() and summary.is_file()):
        return None
    runs = pd.read_parquet(parquet)
    if not set(COLUMNS) <= set(runs.columns):
        return None
    meta = json.loads(summary.read_text())
    wall, workers = float(meta["seconds"]), int(meta.get("workers") or 1)
    cpu = float(runs["cpu_seconds"].sum())
    likelihood = float((runs["likelihood_ms_per_step"] * runs["steps"]).sum() / 1e3)
    selection = 0.0
    if {"selection_ms_per_epoch", "period"} <= set(runs.columns):
        epochs = -(-runs["steps"] // runs["period"].fillna(1).clip(lower=1))
        selection = float((runs["selection_ms_per_epoch"].fillna(0.0) * epochs).sum() / 1e3)
    other = cpu - likelihood - selection
    excess = (wall - RUN_BUDGET_SECONDS) * workers  # CPU seconds to take out of the run
    if excess <= 0:
        needed = 1.0
    else:
        needed = 1.0 / (1.0 - excess / likelihood) if excess < likelihood else math.inf
    return {
        "report": folder.name,
        "wall_seconds": wall,
        "workers": workers,
        "cpu_seconds": cpu,
        "likelihood_share": likelihood / cpu,
        "selection_share": selection / cpu,
        "other_share": other / cpu,
        "parallel_efficiency": cpu / workers / wall,
        "speedup_needed": wall / RUN_BUDGET_SECONDS,
        "likelihood_speedup_needed": needed,
        "wall_if_likelihood_free": wall - likelihood / workers,
    }


def budget(reports: Path) -> list[dict[str, Any]]:
    """:func:`split` of every report folder under ``reports`` that records it, by name."""
    rows = [split(f) for f in sorted(p for p in reports.iterdir() if p.is_dir())]
    return [r for r in rows if r is not None]


def _speedup(x: float) -> str:
    if x <= 1.0:
        return "done"
    return "never" if math.isinf(x) else (f"{x:.2f}x" if x < 100 else "> 100x")


def markdown(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| report | wall min (workers) | CPU s | likelihood | selection | other | "
        "needed overall | likelihood alone | wall min if the likelihood were free |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['report']} | {r['wall_seconds'] / 60:.1f} ({r['workers']}) | "
            f"{r['cpu_seconds']:,.0f} | {r['likelihood_share']:.0%} | "
            f"{r['selection_share']:.0%} | {r['other_share']:.0%} | "
            f"{_speedup(r['speedup_needed'])} | {_speedup(r['likelihood_speedup_needed'])} | "
            f"{r['wall_if_likelihood_free'] / 60:.1f} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reports", type=Path, default=_results.HERE.parent / "reports")
    ap.add_argument("--json", action="store_true", help="print the rows as JSON")
    _results.add_arguments(ap)
    a = ap.parse_args(argv)
    if not a.reports.is_dir():
        raise SystemExit(f"--reports={str(a.reports)!r} is invalid: expected a reports folder")
    run = _results.Run(argv, __file__) if argv is not None else _results.Run()
    rows = budget(a.reports)
    run.save(_results.out_path(a, __file__), rows)
    print(json.dumps(rows) if a.json else markdown(rows))


if __name__ == "__main__":
    main()
