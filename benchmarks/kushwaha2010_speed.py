"""Speed of the Kushwaha 2010 Ch. III pipeline against its real-time budgets.

1. Beamforming: six acoustic nodes, four channels at 100 kHz each. The software beamformer
   (band-pass, 36-beam delay-and-sum over 2^14-sample windows) must process one second of audio
   from all six nodes in less than one second (real-time factor < 1).
2. Fusion: one 4 Hz step of the grid SBE — per-cell likelihoods of 9 sensors (6 beam detection
   functions through their precomputed arc-mean matrices, 3 camera Gaussian mixtures through
   closed-form arc means) on the 2800-cell grid, then the AVCP update. Budget 250 ms.

Wall clock (each the best of ``--repeats``); the CPU seconds (``time.process_time``) of the same
work in ``"cpu"``. BLAS and Numba at their defaults (``--threads T``: T threads for both,
``_results.py``). fusetrack only: no peer.

    python benchmarks/kushwaha2010_speed.py [--repeats 3] [--threads T] [--json] [--save | --out PATH]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from fusetrack.experiments.kushwaha2010.beamformer import realtime_factor
from fusetrack.experiments.kushwaha2010.scene import (
    DT,
    default_layout,
    sbe_filter,
    tick_likelihoods,
)
from fusetrack.management.fusion_scheduler import Packet


def fusion_step_seconds(repeats: int, clock: Callable[[], float] = time.perf_counter) -> float:
    """Seconds for one fusion step with all 9 sensors reporting (best of ``repeats``, by
    ``clock``)."""
    rng = np.random.default_rng(1)
    layout = default_layout()
    a = np.linspace(-0.5, 0.5, 160)
    taken = {sid: Packet(sid, 0, 0.0, 1.0 + rng.random(36)) for sid, *_ in layout.audio}
    for sid, *_ in layout.video:
        taken[sid] = Packet(
            sid, 0, 0.0, 100 * np.exp(-0.5 * ((a - rng.uniform(-0.3, 0.3)) / 0.03) ** 2)
        )
    tick_likelihoods(layout, taken)  # builds the per-sensor arc tables once (cached)
    filt = sbe_filter(layout, "product", "centralized")
    belief = filt.initial()
    best = np.inf
    for _ in range(repeats):
        tic = clock()
        belief = filt.step(belief, DT, tick_likelihoods(layout, taken).measurements(0.0))
        best = min(best, clock() - tic)
    return float(best)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--json", action="store_true")
    _results.add_arguments(p)
    args = p.parse_args(argv)
    run = _results.Run(argv, __file__)
    with _results.limit_threads(args.threads, default_blas=None) as threads:
        run.threads = threads
        result: dict[str, object] = {
            "beamformer_realtime_factor_6_nodes": realtime_factor(nodes=6, repeats=args.repeats),
            "fusion_step_ms_9_sensors_2800_cells": 1e3 * fusion_step_seconds(args.repeats),
        }
        cpu = {
            "beamformer_realtime_factor_6_nodes": realtime_factor(
                nodes=6, repeats=args.repeats, clock=time.process_time
            ),
            "fusion_step_ms_9_sensors_2800_cells": 1e3
            * fusion_step_seconds(args.repeats, time.process_time),
        }
    result["fusion_rate_hz"] = 1e3 / result["fusion_step_ms_9_sensors_2800_cells"]  # type: ignore[operator]
    cpu["fusion_rate_hz"] = 1e3 / cpu["fusion_step_ms_9_sensors_2800_cells"]
    result["cpu"] = cpu
    run.save(_results.out_path(args, __file__), [result])
    if args.json:
        print(json.dumps(result))
    else:
        for k, v in result.items():
            print(f"{k:40s} {v:10.3f}" if isinstance(v, float) else f"{k:40s} {v}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
