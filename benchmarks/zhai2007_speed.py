"""Per-step cost of every Zhai 2007 filter against the bootstrap filter at equal N, and the
complexity statement of Sec. 3.5.4 (MMPF-SP costs O(4 N K) + 3 O(N_s): linear in particles and in
channels; claim C18).

    python benchmarks/zhai2007_speed.py [--N 200 1000] [--steps 30] [--repeats 3] [--clock cpu]
                                        [--threads T] [--json] [--plot PATH] [--save | --out PATH]

Scenario: 2-D CV target, one bearing sensor at the origin (the E2/E13 set-up), ``steps`` steps;
every filter filters the same measurements. Time per step = the fastest of ``--repeats`` runs of
the whole run divided by ``steps`` (one untimed run first: Numba compilation, caches), in CPU
seconds of the process (``--clock wall``: wall seconds; both are measured and saved, each the
fastest of the runs by that clock); BLAS limited to one thread (``--threads T``: BLAS/OpenMP and
Numba get T threads, ``_results.py``). The IMM-EKF has no particles: its cost is the same at
every N (three EKFs). Every filter is fusetrack's (no peer library has them), so there is no
agreement check; the ratios are costs relative to the bootstrap filter.

Filters (Zhai 2007 algorithm in brackets): bootstrap; PF-SP-PEKF (Alg. 1, 20 channels); CPF-SP
(Alg. 2, one bank per active sensor: here one); MM-bootstrap (Alg. 3); MMPF-SP (Alg. 4, 20
channels per model); Galerkin PF (Alg. 5, 100 x 100 grid); discretisation PF (Alg. 6) and its
multiple-model form (Alg. 7); bootstrap + MH-prior / random-walk / independence move (Algs.
8-10); beyond the paper: the unscented-proposal PF and the IMM-EKF (CV + two turns).
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
from fusetrack.core import Gaussian
from fusetrack.experiments.zhai2007.common import run_steps, timed_gaussian
from fusetrack.filters.cpf_sp import CPFSPProposal
from fusetrack.filters.grid_proposals import DiscretisationProposal, GalerkinProposal
from fusetrack.filters.imm import InteractingMultipleModel
from fusetrack.filters.mcmc_moves import IndependenceMove, MHPriorMove, RandomWalkMove
from fusetrack.filters.multiple_model import MultipleModelParticleFilter
from fusetrack.filters.sis import ProposalParticleFilter
from fusetrack.filters.sp_pekf import SPPEKFProposal
from fusetrack.filters.unscented_proposal import UnscentedProposal
from fusetrack.motion import ConstantVelocity, CoordinatedTurn
from fusetrack.motion.maneuver import ManeuverTurn
from fusetrack.sensors import Bearing

PI4 = np.array(
    [[0.7, 0.1, 0.1, 0.1], [0.4, 0.2, 0.2, 0.2], [0.4, 0.2, 0.2, 0.2], [0.4, 0.2, 0.2, 0.2]]
)


def scenario(steps: int, seed: int = 7):
    """``(motion, sensor, prior, zs)``: the model and ``steps`` steps of bearings."""
    return simulate(steps, seed)[:4]


def simulate(steps: int, seed: int = 7):
    """:func:`scenario` and the true states ``(steps, 4)`` at times 1..steps behind ``zs``."""
    rng = np.random.default_rng(seed)
    motion = ConstantVelocity(q=0.05)
    sensor = Bearing("s", position=[0.0, 0.0], sigma=0.05)
    x = np.array([0.0, 50.0, 1.0, -1.0])
    zs, truth = [], []
    for _ in range(steps):
        x = motion.sample(x, 1.0, rng)
        zs.append([sensor.simulate(x, rng)])
        truth.append(x)
    prior = Gaussian(np.array([0.0, 50.0, 1.0, -1.0]), np.diag([1.0, 1.0, 0.1, 0.1]))
    return motion, sensor, prior, zs, np.array(truth)


def mm_models() -> list:
    """The four regimes of the multiple-model filters (transition matrix ``PI4``): the CV of
    :func:`scenario`, turns at +-0.5 m/s^2 (Zhai 2007, Eq. 42) and a CV with ten times the noise."""
    motion = scenario(1)[0]
    return [
        motion,
        ManeuverTurn(0.5, 1, 0.05),
        ManeuverTurn(0.5, -1, 0.05),
        ConstantVelocity(q=0.5),
    ]


def builders(n: int, channels: int = 20) -> dict[str, Callable[[], Callable[..., object]]]:
    motion, sensor, _, _ = scenario(1)
    models = mm_models()

    def sis(prop=None, **kw):
        return lambda: ProposalParticleFilter(motion, [sensor], prop, n, **kw)

    def mm(proposal: str):
        return lambda: MultipleModelParticleFilter(
            models, PI4, [sensor], n, proposal=proposal, n_channels=channels
        )

    turns = [CoordinatedTurn(omega=w, q=0.05) for w in (0.1, -0.1)]
    imm = [[0.9, 0.05, 0.05], [0.1, 0.9, 0.0], [0.1, 0.0, 0.9]]
    return {
        "bootstrap": sis(),
        "PF-SP-PEKF": sis(SPPEKFProposal(channels)),
        "CPF-SP": sis(CPFSPProposal(channels)),
        "MM-bootstrap": mm("prior"),
        "MMPF-SP": mm("sp-pekf"),
        "Galerkin PF": sis(GalerkinProposal(100)),
        "discretisation PF": sis(DiscretisationProposal()),
        "discretisation MMPF": mm("cells"),
        "PF + MH-prior move": sis(None, move=MHPriorMove()),
        "PF + RWM move": sis(None, move=RandomWalkMove(0.2)),
        "PF + MIS move": sis(None, move=IndependenceMove(0.15)),
        "UPF": sis(UnscentedProposal()),
        "IMM-EKF": lambda: InteractingMultipleModel([motion, *turns], imm, [sensor]),
    }


CLOCKS = {"cpu": time.process_time, "wall": time.perf_counter}


def time_filter(make: Callable[[], object], steps: int, repeats: int, clock: str = "cpu") -> float:
    """Seconds per step: the fastest of ``repeats`` timed runs (after one untimed run), by the
    process's CPU time (default; the least disturbed by other processes) or wall time."""
    return time_filter_both(make, steps, repeats)[clock]


def time_filter_both(make: Callable[[], object], steps: int, repeats: int) -> dict[str, float]:
    """``{"cpu": .., "wall": ..}`` seconds per step, each the fastest of ``repeats`` timed runs
    by its clock (after one untimed run)."""
    _, _, prior, zs = scenario(steps)
    out = []
    for r in range(repeats + 1):
        f = make()
        rng = np.random.default_rng(r)
        with _results.Clock() as c:
            if isinstance(f, InteractingMultipleModel):
                timed_gaussian(f, prior, zs, ["s"], 1.0)
            else:  # ProposalParticleFilter, MultipleModelParticleFilter
                run_steps(f, prior, zs, 1.0, rng)
        out.append((c.cpu / steps, c.wall / steps))
    return {"cpu": min(o[0] for o in out[1:]), "wall": min(o[1] for o in out[1:])}


def linear_fit(x: list[int], y: list[float]) -> dict[str, float]:
    """Least-squares ``y = intercept + slope x`` and its R^2."""
    a, b = np.polyfit(x, y, 1)
    pred = a * np.asarray(x) + b
    ss = np.sum((np.asarray(y) - np.mean(y)) ** 2)
    return {"slope": float(a), "intercept": float(b), "r2": float(1 - np.sum((y - pred) ** 2) / ss)}


def scaling(steps: int, repeats: int, clock: str = "cpu") -> dict[str, object]:
    """C18: MMPF-SP seconds per step against particles N_s (10 channels per bank) and against
    channels N per bank (N_s = 200), with linear fits."""
    ns, ks = [500, 1000, 2000, 4000, 8000], [10, 20, 40, 80, 160]
    b_n = [time_filter_both(builders(n, 10)["MMPF-SP"], steps, repeats) for n in ns]
    b_k = [time_filter_both(builders(200, k)["MMPF-SP"], steps, repeats) for k in ks]
    t_n, t_k = [b[clock] for b in b_n], [b[clock] for b in b_k]
    return {
        "N_s": ns,
        "sec_vs_N_s": t_n,
        "fit_N_s": linear_fit(ns, t_n),
        "channels": ks,
        "sec_vs_channels": t_k,
        "fit_channels": linear_fit(ks, t_k),
        "clock": clock,
        "both_vs_N_s": b_n,
        "both_vs_channels": b_k,
    }


def plot_scaling(sc: dict[str, object], path: str) -> None:
    """Two panels: seconds per step against N_s and against channels, points and linear fit."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for ax, key, label in zip(axes, ("N_s", "channels"), ("particles N_s", "EKF channels N")):
        x = np.asarray(sc[key], float)
        y = np.asarray(sc[f"sec_vs_{key}"], float) * 1e3
        f = sc[f"fit_{key}"]
        ax.plot(x, y, "o", label="measured")
        ax.plot(
            x, (f["intercept"] + f["slope"] * x) * 1e3, "-", label=f"linear fit, R² {f['r2']:.3f}"
        )
        ax.set(xlabel=label, ylabel="ms per step")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title("MMPF-SP, 4 models x 10 channels", fontsize=9)
    axes[1].set_title("MMPF-SP, 4 models, N_s = 200", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--N", type=int, nargs="+", default=[200, 1000])
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--filters", nargs="+", default=None)
    ap.add_argument("--no-scaling", action="store_true")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--clock", choices=list(CLOCKS), default="cpu")
    ap.add_argument("--plot", default=None, help="write the C18 scaling figure to this PNG")
    _results.add_arguments(ap)
    args = ap.parse_args(argv)
    if args.threads is not None and args.threads < 1:
        ap.error("--threads must be >= 1")
    run, rows = _results.Run(argv, __file__), []
    with _results.limit_threads(args.threads) as threads:  # default: BLAS one thread
        run.threads = threads
        results = _measure(args, rows)
    if args.json:
        print(json.dumps(results, default=float))
    run.save(_results.out_path(args, __file__), rows)
    return 0


def _measure(args: argparse.Namespace, rows: list[dict]) -> dict[str, object]:
    """The ``--json`` document; ``rows`` gets one results row per N (and the C18 scaling)."""
    results: dict[str, object] = {}
    for n in args.N:
        b = builders(n)
        names = args.filters or list(b)
        both = {m: time_filter_both(b[m], args.steps, args.repeats) for m in names}
        if "bootstrap" not in both:
            both["bootstrap"] = time_filter_both(b["bootstrap"], args.steps, args.repeats)
        per = {m: both[m][args.clock] for m in names}
        rel = {c: {m: both[m][c] / both["bootstrap"][c] for m in names} for c in CLOCKS}
        results[f"N={n}"] = {"seconds_per_step": per, "relative_to_bootstrap": rel[args.clock]}
        rows.append(
            {
                "N": n,
                "steps": args.steps,
                "clock": args.clock,
                "seconds_per_step": per,
                "cpu_seconds_per_step": {m: both[m]["cpu"] for m in names},
                "wall_seconds_per_step": {m: both[m]["wall"] for m in names},
                "relative_to_bootstrap": rel[args.clock],
                "cpu_relative_to_bootstrap": rel["cpu"],
                "wall_relative_to_bootstrap": rel["wall"],
            }
        )
        if not args.json:
            print(f"N = {n}: seconds per step, {args.clock} (x bootstrap; wall / cpu)")
            for m in names:
                print(
                    f"  {m:20s} {per[m]:.5f}  ({rel[args.clock][m]:.1f}x; "
                    f"{rel['wall'][m]:.1f}x / {rel['cpu'][m]:.1f}x)"
                )
    if not args.no_scaling:
        sc = scaling(args.steps, args.repeats, args.clock)
        results["C18_scaling"] = sc
        rows.append({"C18_scaling": sc})
        if args.plot:
            plot_scaling(sc, args.plot)
        if not args.json:
            for key in ("N_s", "channels"):
                ms = ", ".join(f"{t * 1e3:.2f}" for t in sc[f"sec_vs_{key}"])  # type: ignore[attr-defined]
                print(f"C18 MMPF-SP ms/step vs {key} {sc[key]}: {ms}; fit {sc[f'fit_{key}']}")
    return results


if __name__ == "__main__":
    raise SystemExit(main())
