"""The experiment registry and the one way every experiment is run (DESIGN.md contract).

An experiment is a module with ``run(ctx: RunContext) -> Outcome``. The registry maps a name to
``module:function`` so that ``fusetrack list`` does not import every experiment.
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass
from typing import Any

from ..core.errors import UnknownExperimentError
from ..evaluation.report import Outcome, RunContext, peak_memory_mb, write_outputs


@dataclass(frozen=True)
class ExperimentInfo:
    name: str
    target: str  # "module:function", relative to fusetrack.experiments
    title: str
    paper: str


REGISTRY: dict[str, ExperimentInfo] = {
    info.name: info
    for info in [
        ExperimentInfo(
            "demo",
            "demo:run",
            "Demo: one manoeuvring target, two microphone arrays, a camera and a radio tag; "
            "EKF, UKF and particle filter against the posterior CRLB",
            "fusetrack",
        ),
        ExperimentInfo(
            "zhai2007-scalar",
            "zhai2007_scalar:run",
            "Zhai 2007 E1 (Tables 2-3): EKF, bootstrap and PF-SP-PEKF on the scalar benchmark",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "zhai2007-mcmc",
            "zhai2007_mcmc:run",
            "Zhai 2007 E19 (Table 15): particle filters with MH, random-walk and independence moves",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "lee2009-projected-planes",
            "lee2009_projected_planes:run",
            "Lee 2009 Ch. 2: 3-D acoustic tracking on projected planes (PPS) vs direct 3-D, with CRLB",
            "Lee 2009 (seed 000)",
        ),
    ]
}


def describe(name: str) -> ExperimentInfo:
    try:
        return REGISTRY[name]
    except KeyError:
        raise UnknownExperimentError(
            f"experiment={name!r} is unknown: expected one of {sorted(REGISTRY)} (see `fusetrack list`)"
        ) from None


def run_experiment(ctx: RunContext) -> dict[str, Any]:
    """Run the experiment ``ctx.name`` and write its three output files; return the summary."""
    info = describe(ctx.name)
    module_name, func_name = info.target.split(":")
    fn = getattr(importlib.import_module(f"{__package__}.{module_name}"), func_name)
    start = time.perf_counter()
    outcome: Outcome = fn(ctx)
    if not outcome.title:
        outcome.title = info.title
    return write_outputs(ctx, outcome, time.perf_counter() - start, peak_memory_mb())
