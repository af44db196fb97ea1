"""``fusetrack reproduce [NAME ...|--all] --out reports/``: regenerate full-size reports.

Each experiment runs as ``fusetrack run NAME --seed 0 --out OUT/NAME`` with its default (the
paper's) number of runs, one after the other, as the committed reports' headers show; a line on
stderr says which one is running and how it ended. Into a reports folder (one with a
README.md) it then rewrites the generated blocks (`fusetrack reports tally --write`).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from ..core import ConfigError, invalid
from ..evaluation import Claim, RunContext, verdict_line
from ..experiments import REGISTRY, describe, run_experiment
from .report_tally import refresh_reports_folder

NOT_REPORTED = ("demo",)  # experiments with no folder under reports/


def reproduce_names(names: list[str], all_: bool) -> list[str]:
    """The experiments to run: ``names`` (each checked) or, with ``--all``, every reported one."""
    if all_ == bool(names):
        raise ConfigError(invalid("NAME", names, "experiment names or --all, not both or neither"))
    if all_:
        return [n for n in REGISTRY if n not in NOT_REPORTED]
    return [describe(n).name for n in names]


def add_reproduce_parser(sub: Any) -> None:
    p = sub.add_parser(
        "reproduce",
        help="rerun experiments at full size (seed 0, default runs) into OUT/NAME, one at a time",
    )
    p.add_argument("names", nargs="*", metavar="NAME", help="experiments (see `fusetrack list`)")
    p.add_argument("--all", action="store_true", help="every experiment with a report")
    p.add_argument("--out", type=Path, required=True, help="reports folder (e.g. reports/)")
    p.add_argument("--quick", action="store_true", help="quick runs instead (for a smoke test)")
    p.add_argument("--workers", type=int, default=None, help="worker processes per experiment")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bars")


def run_reproduce_command(args: argparse.Namespace) -> int:
    names = reproduce_names(args.names, args.all)
    for i, name in enumerate(names, 1):
        out = args.out / name
        print(f"[{i}/{len(names)}] {name} -> {out}", file=sys.stderr, flush=True)
        start = time.perf_counter()
        ctx = RunContext(
            name=name,
            out_dir=out,
            quick=args.quick,
            seed=0,
            workers=args.workers,
            progress=False if args.no_progress else None,
        )
        summary = run_experiment(ctx)
        verdict = verdict_line([Claim(**c) for c in summary["claims"]])
        seconds = time.perf_counter() - start
        print(
            f"[{i}/{len(names)}] {name}: {verdict} ({seconds:.0f} s)", file=sys.stderr, flush=True
        )
    if names and not args.quick:  # into a reports folder: its tally and verdicts follow
        note = refresh_reports_folder(args.out / names[0])
        if note:
            print(note, file=sys.stderr, flush=True)
    return 0
