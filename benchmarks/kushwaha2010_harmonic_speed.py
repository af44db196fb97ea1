"""Speed of Kushwaha 2010 Ch. IV localisation (Alg. 1) against the node's 4 Hz feature cycle.

The FPGA nodes deliver a beamform and a compressed PSD every ≈ 250 ms (Ch. IV hardware), so the
base station has 250 ms for one step of Alg. 1: N = 40 Gibbs sweeps over the fundamentals and
then over the positions. Measured here for four sources on the Table 10 network, as CPU time
(process time: robust on a shared machine) and reported as ratios:

* ``sweep_ms_4_sources``: one Gibbs sweep (M slice-sampled fundamentals + 2M slice-sampled
  coordinates + the pairwise swap moves), from the difference between 41 and 1 sweeps;
* ``step_to_cycle_ratio``: one whole step (initialisation + 40 sweeps) / 250 ms (< 1: real time).

The same figures by the wall clock are in ``"wall"``. BLAS and Numba at their defaults
(``--threads T``: T threads for both, ``_results.py``). fusetrack only: no peer.

    python benchmarks/kushwaha2010_harmonic_speed.py [--repeats 3] [--threads T] [--json]
        [--save | --out PATH]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from fusetrack.experiments.kushwaha2010.harmonic_sources import (
    SENSORS,
    network,
    simulate_features,
)
from fusetrack.perception.source_localisation import BeamformModel, localise
from fusetrack.world.harmonic_sources import random_sources

CYCLE_SECONDS = 0.25


def step_seconds(features, n_sources: int, sweeps: int, repeats: int) -> dict[str, float]:
    """Least CPU and least wall time (``{"cpu", "wall"}``) of ``repeats`` Alg. 1 steps with
    ``sweeps`` Gibbs sweeps."""
    net = network()
    best = {"cpu": np.inf, "wall": np.inf}
    for r in range(repeats):
        rng = np.random.default_rng(r)
        wall, cpu = _results.timed(
            lambda rng=rng: localise(
                net, features, n_sources, rng, model=BeamformModel(n_samples=sweeps)
            )
        )
        best = {"cpu": min(best["cpu"], cpu), "wall": min(best["wall"], wall)}
    return best


def summary(one: float, full: float) -> tuple[float, float]:
    """Seconds of one sweep and of a 40-sweep step from the 1- and 41-sweep times."""
    sweep = max(full - one, 0.0) / 40
    return sweep, one + 39 * sweep


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sources", type=int, default=4)
    ap.add_argument("--json", action="store_true")
    _results.add_arguments(ap)
    args = ap.parse_args()
    run = _results.Run()
    rng = np.random.default_rng(0)
    sources = random_sources(args.sources, rng, avoid=SENSORS)
    feats = simulate_features(sources, network(), 25.0, rng)
    with _results.limit_threads(args.threads, default_blas=None) as threads:
        run.threads = threads
        one = step_seconds(feats, args.sources, 1, args.repeats)
        full = step_seconds(feats, args.sources, 41, args.repeats)
    sweep, step40 = summary(one["cpu"], full["cpu"])
    w_sweep, w_step40 = summary(one["wall"], full["wall"])
    out = {
        "sources": args.sources,
        "sweep_ms_4_sources": round(1e3 * sweep, 2),
        "step_ms_40_sweeps": round(1e3 * step40, 1),
        "step_to_cycle_ratio": round(step40 / CYCLE_SECONDS, 3),
        "clock": "process_time",
        "wall": {
            "sweep_ms_4_sources": round(1e3 * w_sweep, 2),
            "step_ms_40_sweeps": round(1e3 * w_step40, 1),
            "step_to_cycle_ratio": round(w_step40 / CYCLE_SECONDS, 3),
        },
    }
    run.save(_results.out_path(args, __file__), [out])
    if args.json:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print(f"{k:24s} {v}")


if __name__ == "__main__":
    main()
