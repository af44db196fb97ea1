"""Per-step cost of the Zhai 2007 filters against the bootstrap filter at equal N, and the
complexity statement of Sec. 3.5.4 (MMPF-SP costs O(4 N K) + 3 O(N_s): linear in particles and in
channels; claim C18).

    python benchmarks/zhai2007_speed.py [--N 200 1000] [--steps 30] [--json]

Scenario: 2-D CV target, one bearing sensor at the origin (the E2/E13 set-up), ``steps`` steps;
every filter filters the same measurements. Time per step = median over ``--repeats`` runs of
the whole run divided by ``steps`` (the first run warms up Numba).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from collections.abc import Callable

import numpy as np

from fusetrack.core import Gaussian
from fusetrack.filters.grid_proposals import DiscretisationProposal, GalerkinProposal
from fusetrack.filters.mcmc_moves import RandomWalkMove
from fusetrack.filters.multiple_model import MultipleModelParticleFilter, run_mm
from fusetrack.filters.sis import ProposalParticleFilter, run_sis
from fusetrack.filters.sp_pekf import SPPEKFProposal
from fusetrack.motion import ConstantVelocity
from fusetrack.motion.maneuver import ManeuverTurn
from fusetrack.sensors import Bearing

PI4 = np.array(
    [[0.7, 0.1, 0.1, 0.1], [0.4, 0.2, 0.2, 0.2], [0.4, 0.2, 0.2, 0.2], [0.4, 0.2, 0.2, 0.2]]
)


def scenario(steps: int, seed: int = 7):
    rng = np.random.default_rng(seed)
    motion = ConstantVelocity(q=0.05)
    sensor = Bearing("s", position=[0.0, 0.0], sigma=0.05)
    x = np.array([0.0, 50.0, 1.0, -1.0])
    zs = []
    for _ in range(steps):
        x = motion.sample(x, 1.0, rng)
        zs.append([sensor.simulate(x, rng)])
    prior = Gaussian(np.array([0.0, 50.0, 1.0, -1.0]), np.diag([1.0, 1.0, 0.1, 0.1]))
    return motion, sensor, prior, zs


def builders(n: int, channels: int = 20) -> dict[str, Callable[[], Callable[..., object]]]:
    motion, sensor, _, _ = scenario(1)
    models = [
        motion,
        ManeuverTurn(0.5, 1, 0.05),
        ManeuverTurn(0.5, -1, 0.05),
        ConstantVelocity(q=0.5),
    ]

    def sis(prop=None, **kw):
        return lambda: ProposalParticleFilter(motion, [sensor], prop, n, **kw)

    def mm(proposal: str):
        return lambda: MultipleModelParticleFilter(
            models, PI4, [sensor], n, proposal=proposal, n_channels=channels
        )

    return {
        "bootstrap": sis(),
        "PF-SP-PEKF": sis(SPPEKFProposal(channels)),
        "PF-RWM": sis(None, move=RandomWalkMove(0.2)),
        "Galerkin PF": sis(GalerkinProposal(100)),
        "discretisation PF": sis(DiscretisationProposal()),
        "MM-bootstrap": mm("prior"),
        "MMPF-SP": mm("sp-pekf"),
    }


def time_filter(make: Callable[[], object], steps: int, repeats: int) -> float:
    _, _, prior, zs = scenario(steps)
    out = []
    for r in range(repeats + 1):
        f = make()
        rng = np.random.default_rng(r)
        t0 = time.perf_counter()
        if isinstance(f, MultipleModelParticleFilter):
            run_mm(f, prior, zs, 1.0, rng)
        else:
            run_sis(f, prior, zs, 1.0, rng)  # type: ignore[arg-type]
        out.append((time.perf_counter() - t0) / steps)
    return statistics.median(out[1:])


def scaling(steps: int, repeats: int) -> dict[str, object]:
    """C18: MMPF-SP seconds per step against N_s (K fixed) and K (N_s fixed), with linear fits."""
    ns, ks = [200, 400, 800, 1600], [5, 10, 20, 40]
    t_n = [time_filter(builders(n, 10)["MMPF-SP"], steps, repeats) for n in ns]
    t_k = [time_filter(builders(200, k)["MMPF-SP"], steps, repeats) for k in ks]

    def fit(x, y):
        a, b = np.polyfit(x, y, 1)
        pred = a * np.asarray(x) + b
        r2 = 1 - np.sum((np.asarray(y) - pred) ** 2) / np.sum((np.asarray(y) - np.mean(y)) ** 2)
        return {"slope": a, "intercept": b, "r2": r2}

    return {
        "N_s": ns,
        "sec_vs_N_s": t_n,
        "fit_N_s": fit(ns, t_n),
        "K": ks,
        "sec_vs_K": t_k,
        "fit_K": fit(ks, t_k),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--N", type=int, nargs="+", default=[200, 1000])
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--filters", nargs="+", default=None)
    ap.add_argument("--no-scaling", action="store_true")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    results: dict[str, object] = {}
    for n in args.N:
        b = builders(n)
        names = args.filters or list(b)
        per = {m: time_filter(b[m], args.steps, args.repeats) for m in names}
        base = per.get("bootstrap") or time_filter(b["bootstrap"], args.steps, args.repeats)
        results[f"N={n}"] = {
            "seconds_per_step": per,
            "relative_to_bootstrap": {m: t / base for m, t in per.items()},
        }
        if not args.json:
            print(f"N = {n}: seconds per step (x bootstrap)")
            for m, t in per.items():
                print(f"  {m:20s} {t:.5f}  ({t / base:.1f}x)")
    if not args.no_scaling:
        sc = scaling(args.steps, args.repeats)
        results["C18_scaling"] = sc
        if not args.json:
            print(
                "C18 MMPF-SP: s/step vs N_s",
                [f"{t:.4f}" for t in sc["sec_vs_N_s"]],
                "fit",
                sc["fit_N_s"],
            )
            print(
                "C18 MMPF-SP: s/step vs K  ",
                [f"{t:.4f}" for t in sc["sec_vs_K"]],
                "fit",
                sc["fit_K"],
            )
    if args.json:
        print(json.dumps(results, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
