"""CPU time of the full-size E1 (``ercan2013-cameras``: 3 prior levels x 8 camera counts x 5 runs x
4000 steps, L = 1000) estimated from short runs of every configuration through the same code path
(issue 4, "Speed and scale": the bar is 15 minutes on the 2-core machine).

    python benchmarks/ercan2013_e1_cost.py [--steps 300] [--json]

Process (CPU) time, not wall time: on a machine shared by several jobs wall time says little.
The world (walkers, readings) is simulated once per seed and shared by the 24 configurations.
"""

from __future__ import annotations

import argparse
import json
import time

from fusetrack.experiments.ercan2013.cameras import PRIORS, SIGMA_PSI
from fusetrack.experiments.ercan2013.scenes import get_scene
from fusetrack.experiments.ercan2013.simulation import run_tracking, world_and_readings

FULL_STEPS, FULL_RUNS, CAMERAS = 4000, 5, range(1, 9)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    run_tracking({"steps": 5, "particles": 50}, 0)  # compile the kernels first
    t = time.process_time()
    world_and_readings(get_scene("square"), 40, a.steps, a.seed)
    world = (time.process_time() - t) / a.steps
    per_step: dict[str, float] = {}
    for prior in PRIORS:
        for k in CAMERAS:
            cfg = {"prior": prior, "sigma_psi": SIGMA_PSI, "k": k, "method": "fixed"}
            t = time.process_time()
            run_tracking({**cfg, "steps": a.steps, "particles": 1000}, a.seed)
            per_step[f"{prior} k={k}"] = (time.process_time() - t) / a.steps
    total = (sum(per_step.values()) + world) * FULL_STEPS * FULL_RUNS
    out = {
        "sample_steps": a.steps,
        "world_ms_per_step": 1e3 * world,
        "tracker_ms_per_step": {key: round(1e3 * v, 3) for key, v in per_step.items()},
        "full_e1_cpu_minutes": total / 60,
        "full_e1_minutes_on_two_idle_cores": total / 120,
    }
    if a.json:
        print(json.dumps(out))
    else:
        for key, v in out.items():
            print(f"{key:36s} {v:.2f}" if isinstance(v, float) else f"{key:36s} {v}")


if __name__ == "__main__":
    main()
