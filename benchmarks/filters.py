"""Per-particle cost of every particle-filter variant against the bootstrap filter on its paper's
model, beside the variant's arithmetic (issue 21, item 2).

    python benchmarks/filters.py [--N 1000 10000 100000] [--steps 5] [--repeats 2]
                                 [--variants NAME ...] [--budget 480] [--threads T]
                                 [--json] [--save | --out PATH]
    python benchmarks/filters.py --table benchmarks/results/filters.json   # README table

Families and models (scenario builders imported from the experiments / other benchmarks, not
re-written):

* ``zhai2007``: the 2-D CV target and one bearing sensor of ``zhai2007_speed.py`` (E2/E13);
  every filter of :func:`zhai2007_speed.builders` that has particles -- PF-SP-PEKF (EKF bank of
  20 channels), CPF-SP, multiple-model bootstrap and MMPF-SP (4 models), Galerkin PF (100 x 100
  grid), discretisation PF / MMPF, bootstrap + MH-prior / random-walk / independence moves, the
  unscented-proposal PF. Baseline: its ``bootstrap``.
* ``ercan2013``: Algorithm 1's ASIR (:class:`~fusetrack.filters.WaypointASIR`) in the square
  room with 8 cameras and 40 moving occluders with Gaussian priors, reading the occlusion-aware
  likelihood (Eqs. 6-9, :class:`~fusetrack.sensors.occlusion_aware_camera.OcclusionAwareLikelihood`,
  as ``ercan2013_speed.py`` sets it up). Baseline: the same ASIR with a Gaussian position fix
  (the cheapest likelihood on the same model).
* ``kushwaha2010``: the grid-free back end (:class:`~fusetrack.filters.DetectionParticleFilter`)
  on the six acoustic nodes' beam detection functions and the three cameras' Gaussian mixtures
  of ``default_layout()`` (AVCP). Baseline: the same engine with a Gaussian bearing sensor at
  each of the nine nodes.

Time per step = the fastest of ``--repeats`` timed runs of ``--steps`` steps (predict + update +
resample, whatever the variant does in a step) after one untimed run (Numba compilation),
divided by ``steps``; per particle = that over N. Both clocks (``_results.Clock``: CPU of every
thread and wall). BLAS on one thread unless ``--threads``. A size whose predicted cost (the
last measured size scaled by the variant's growth, linear or quadratic in N) would overrun the
variant's share of ``--budget`` CPU seconds is skipped and listed under ``"skipped"``.

Operations per particle (``OPS`` below, derived in its comments): floating-point operations of
the algorithm as the paper states it, a transcendental function (exp, log, atan2, erf) or a
normal/uniform draw counted as one operation, per-step work shared by all particles (an EKF
bank, a grid FFT) divided by N. ``ns_per_op`` = measured CPU per particle / operations: a
variant "at its arithmetic" has about the bootstrap's ns per operation; one far above it spends
its time elsewhere (Python, allocation, memory traffic). ``above_arithmetic`` = (CPU time over
the baseline's) / (operations over the baseline's): 1 at the baseline's cost per operation.

Peers: ``filter_peers.py`` times the variants a peer library implements (bootstrap, the
unscented proposal through Stone Soup's ``KalmanProposal``, the multiple-model bootstrap) against
the peers' own implementations on the Zhai 2007 model, with an RMSE agreement check, and lists
every other variant with the reason it has no peer. This script is fusetrack only: no agreement
check.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
import zhai2007_speed

# --------------------------------------------------------------------------------------------
# operations per particle per step: (per particle, per step shared by all particles, per pair
# of particles). d = 4 (state), one bearing unless said. Counting: a dense d x d mat-vec is
# 2 d^2 = 32; drawing d correlated normals d + 2 d^2 = 36; a d x d Cholesky d^3 / 3 ~ 21; a
# d x d triangular solve d^2 = 16; a Gaussian log-density with a factored covariance
# d^2 + 2 d = 24; exp / log / atan2 / a draw: 1.
BOOT = 32 + 36 + 1 + 3 + 3 + 6 + 4 + 4
# bootstrap: F x (32) + noise (36) + atan2 (1) + residual and wrap (3) + Gaussian log-lik (3) +
# log-weight add, max, exp, sum, divide, ESS (6) + systematic resample: uniform, compare, index
# (4) + copy of d values (4) = 89.
EKF = 4 * 4**3 + 2 * 4**2 + 10 + 6 * 4**3 + 4 * 4**2
# one EKF channel: predict F P F^T (4 d^3 = 256) + Q (2 d^2 = 32) + bearing Jacobian (10) +
# Joseph-form update (6 d^3 = 384) + S, gain, mean (4 d^2 = 64) = 746.
SP_PARTICLE = BOOT + 36 + 24 + 24
# PF-SP-PEKF per particle: the bootstrap's work + a draw from the bank's moment-matched Gaussian
# (36) + its log-density (24) + the transition log-density (24) = 173; per step: 20 channels of
# EKF (746 each) + moment matching (20 x (d + d^2) x 2 = 800) + Cholesky of R_total (21).
SP_STEP = 20 * EKF + 800 + 21
UPF = BOOT + 9 * 32 + 9 * 2 * 16 + 9 * 6 + 9 * 2 * 4 + 2 * 4**2 + 21 + 36 + 24 + 24
# unscented proposal per particle: 2d+1 = 9 sigma points through F (9 x 32) + predicted
# covariance (9 outer products, 9 x 2 d^2 = 288) + bearing of each point (9 x 6) + cross
# covariance (9 x 2 d = 72) + covariance update (2 d^2 = 32) + Cholesky of S_i (21) + draw (36) +
# proposal and transition log-densities (24 + 24) + the bootstrap's work = 944.
MM_EXTRA = 4 + 1
# multiple-model: a regime draw from the Markov row (uniform + 4 compares) per particle.
GRID = 100 * 100
GALERKIN_STEP = GRID * (2 * 5 * math.log2(GRID) / 2 + 6 + 10)
# Galerkin per step: two 2-D FFTs and one inverse (3 x 2.5 n log2 n ~ 5 n log2 n for n = 10^4)
# + kernel and histogram (6 per cell) + likelihood on every cell (10 per cell).
GALERKIN_PARTICLE = BOOT + 14 + 3 + 12 + 36
# Galerkin per particle: inverse-CDF cell draw (log2 10^4 ~ 14 compares) + uniform in cell (3) +
# conditional completion of the velocity (12) + its draw (36) + the bootstrap's work.
PAIR = 12
# the marginal weight p^(p) = (1/N) sum_j N(p; f(x_j)_pos, Q_pp) and the ancestor draw: per pair
# (particle, ancestor) a 2-D Gaussian exponent (difference 2, quadratic form 6, exp 1, add and
# running-sum / compare 3) = 12: O(N) per particle, as the algorithm states it.
CELLS = 400
DISC_PARTICLE = BOOT + 3 + 9 + 3 * CELLS + 12 + 36
# discretisation per particle: cell draw (3 + log2 400 ~ 9) + the box-density q(p) summed over
# at most 400 cells (3 per cell) + completion (12 + 36) + the bootstrap's work.
MOVE_PRIOR = BOOT + 36 + 32 + 1 + 3 + 3 + 2
# MH-prior move: a fresh draw from the transition (32 + 36), its bearing (1 + 3) and
# log-likelihood (3), accept test (uniform + compare, 2).
MOVE_RW = BOOT + 4 + 4 + 1 + 3 + 3 + 24 + 2
# random-walk move: d normals (4) + add (4) + bearing (1 + 3) + log-lik (3) + transition
# log-density at the proposal (24) + accept (2).
MOVE_MIS = MOVE_RW
# independence move: the same count (draw, target log-density, accept).
OCC_K, OCC_M = 8, 40
OCC_LIK = OCC_K * (10 + 15 + 5) + OCC_K * OCC_M * 20 + OCC_K**2
# occlusion-aware likelihood per particle: per camera the projection (10), field of view and
# static occluder test (15) and reading density (5); per camera and moving occluder the
# probability that the Gaussian occluder lies in the exclusion-shortened rectangle between camera
# and particle (projection onto the segment, normal variance, two erf: 20); the pattern
# recursion over cameras (k^2 = 64): 6784, the likelihood as Eqs. 6-9 state it. The kernels
# (world/occlusion_kernels.py) skip (camera, particle, occluder) triples more than 5 standard
# deviations from the ray, so they do a small fraction of this: ns/op well under the bootstrap's
# means the pruning, not a faster machine.
ASIR_BASE = 60 + 4 + 6 + 4 + 5
# ASIR per particle without the likelihood: waypoint-regime dynamics (regime draw, heading,
# speed, step, wall test: 60) + first-stage weights (4) + ancestors (6) + copy (4) + weights (5).
DET_AUDIO, DET_VIDEO = 15, 30
DET_LIK = 6 * DET_AUDIO + 3 * DET_VIDEO + 9 + 9
# detection functions per particle: 6 acoustic nodes x (relative position 2, atan2 1, heading
# and wrap 3, beam index 3, linear interpolation 3, normalise 3 = 15) + 3 cameras x (bearing 6
# + Gaussian mixture of ~3 components, 8 each = 30) + log and sum over the 9 sensors (18) = 198.
GAUSS9 = 9 * 10
# nine Gaussian bearings per particle: relative position, atan2, wrap, log-lik (10 each).

OPS: dict[str, tuple[float, float, float]] = {
    "bootstrap": (BOOT, 0, 0),
    "PF-SP-PEKF": (SP_PARTICLE, SP_STEP, 0),
    "CPF-SP": (SP_PARTICLE, SP_STEP, 0),
    "MM-bootstrap": (BOOT + MM_EXTRA, 0, 0),
    "MMPF-SP": (SP_PARTICLE + MM_EXTRA, 4 * SP_STEP, 0),
    "Galerkin PF": (GALERKIN_PARTICLE, GALERKIN_STEP, PAIR),
    "discretisation PF": (DISC_PARTICLE, 0, PAIR),
    "discretisation MMPF": (DISC_PARTICLE + MM_EXTRA, 0, PAIR),
    "PF + MH-prior move": (MOVE_PRIOR, 0, 0),
    "PF + RWM move": (MOVE_RW, 0, 0),
    "PF + MIS move": (MOVE_MIS, 0, 0),
    "UPF": (UPF, 0, 0),
    "ASIR, position fix": (ASIR_BASE + 2 * 8, 0, 0),
    "ASIR, occlusion-aware": (ASIR_BASE + 2 * OCC_LIK, 0, 0),
    "bootstrap, 9 Gaussian bearings": (BOOT - 7 + GAUSS9, 0, 0),
    "detection-function PF": (BOOT - 7 + DET_LIK, 0, 0),
}
# quadratic variants: the number of (particle, ancestor) pairs grows as N^2
QUADRATIC = {"Galerkin PF", "discretisation PF", "discretisation MMPF"}


def operations(name: str, n: int) -> float:
    """Operations per particle of ``name`` at ``n`` particles: own + shared / n + pairs * n."""
    own, shared, pair = OPS[name]
    return own + shared / n + pair * n


# --------------------------------------------------------------------------------------------
# the models


@dataclass(frozen=True)
class Case:
    """One variant on its model: ``family``, the baseline's name, and ``run(n, steps, seed)``
    running ``steps`` steps with ``n`` particles (built outside the clock by ``build``)."""

    family: str
    baseline: str
    build: Callable[[int, int, int], Callable[[], object]]


def _zhai_case(name: str) -> Case:
    def build(n: int, steps: int, seed: int) -> Callable[[], object]:
        from fusetrack.experiments.zhai2007.common import run_steps

        make = zhai2007_speed.builders(n)[name]
        _, _, prior, zs = zhai2007_speed.scenario(steps)
        filt = make()
        rng = np.random.default_rng(seed)
        return lambda: run_steps(filt, prior, zs, 1.0, rng)

    return Case("zhai2007", "bootstrap", build)


ZHAI = [
    "bootstrap",
    "PF-SP-PEKF",
    "CPF-SP",
    "MM-bootstrap",
    "MMPF-SP",
    "Galerkin PF",
    "discretisation PF",
    "discretisation MMPF",
    "PF + MH-prior move",
    "PF + RWM move",
    "PF + MIS move",
    "UPF",
]


@dataclass(frozen=True)
class _PositionFix:
    """``N(z; x, sigma^2 I)`` on positions: the cheapest likelihood on the ASIR's model."""

    sigma: float = 1.0
    sensor_id: str = "cameras"

    def log_likelihood(self, z: Any, x: np.ndarray) -> np.ndarray:
        return -0.5 * np.sum((x - z) ** 2, axis=-1) / self.sigma**2


def _ercan_case(occlusion: bool) -> Case:
    def build(n: int, steps: int, seed: int) -> Callable[[], object]:
        from fusetrack.core import Measurement
        from fusetrack.experiments.ercan2013.scenes import square_scene
        from fusetrack.filters import WaypointASIR
        from fusetrack.motion import WaypointRegimeDynamics
        from fusetrack.sensors.occlusion_aware_camera import (
            CameraNetworkReport,
            OcclusionAwareCameraSensor,
            OcclusionAwareLikelihood,
        )
        from fusetrack.world.occlusion import OccluderPriors

        rng = np.random.default_rng(seed)
        sq = square_scene(True)
        cams = np.arange(min(OCC_K, len(sq.cameras)))
        truth = sq.room.sample_free(rng, 1)[0]
        pri = OccluderPriors(
            sq.room.sample_free(rng, OCC_M), np.broadcast_to(16.0 * np.eye(2), (OCC_M, 2, 2))
        )
        lik = OcclusionAwareLikelihood(sq.cameras, sq.room, 3.33, "gaussian", exclusion=3.33)
        z = sq.cameras.subset(cams).image_coordinate(truth[None, :])
        z[~lik.assigned(cams, truth[None, :])[:, 0]] = np.nan
        sensor: Any
        if occlusion:
            sensor, value = OcclusionAwareCameraSensor(lik), CameraNetworkReport(z, cams, pri)
        else:
            sensor, value = _PositionFix(5.0), truth
        asir = WaypointASIR(
            sq.room, WaypointRegimeDynamics(sigma_v=sq.motion_noise), n, sq.speed, sensors=(sensor,)
        )
        belief0 = asir.initialize(rng)
        zs = [[Measurement(float(t), "cameras", value)] for t in range(1, steps + 1)]

        def run() -> object:
            b = belief0
            for step in zs:
                b = asir.step(b, 1.0, step, rng)
            return b

        return run

    return Case("ercan2013", "ASIR, position fix", build)


def _kushwaha_case(detection: bool) -> Case:
    def build(n: int, steps: int, seed: int) -> Callable[[], object]:
        from fusetrack.core import Measurement
        from fusetrack.experiments.kushwaha2010.scene import (
            bearing_detections,
            default_layout,
            detection_sensors,
        )
        from fusetrack.filters import DetectionParticleFilter, ParticleFilter
        from fusetrack.management.fusion_scheduler import Packet
        from fusetrack.motion import ConstantVelocity
        from fusetrack.sensors import Bearing

        rng = np.random.default_rng(seed)
        layout = default_layout()
        motion = ConstantVelocity(ndim=2, q=4.0)
        a = np.linspace(-0.5, 0.5, 160)
        taken = {sid: Packet(sid, 0, 0.0, 1.0 + rng.random(36)) for sid, *_ in layout.audio}
        for sid, *_ in layout.video:
            peak = np.exp(-0.5 * ((a - rng.uniform(-0.3, 0.3)) / 0.03) ** 2)
            taken[sid] = Packet(sid, 0, 0.0, 100 * peak)
        centre = np.array([17.5, 10.0])
        pos = centre + rng.normal(0.0, 2.0, (n, 2))
        filt: Any
        if detection:
            filt = DetectionParticleFilter(motion, detection_sensors(layout), n)
            zs = [
                bearing_detections(layout, taken, ("audio", "video"), float(t))
                for t in range(steps)
            ]
            belief0 = filt.initial_belief(pos, 8.0, rng)
        else:
            nodes = [(sid, x, y) for sid, x, y, _ in (*layout.audio, *layout.video)]
            sensors = {sid: Bearing(sid, position=[x, y], sigma=0.1) for sid, x, y in nodes}
            filt = ParticleFilter(motion, sensors, n, ess_threshold=1.0)
            zs = [
                [
                    Measurement(float(t), sid, np.arctan2(centre[1] - y, centre[0] - x))
                    for sid, x, y in nodes
                ]
                for t in range(steps)
            ]
            # the same initial cloud (initial_belief only uses the shared engine's helpers)
            belief0 = DetectionParticleFilter.initial_belief(filt, pos, 8.0, rng)

        def run() -> object:
            b = belief0
            for step in zs:
                b = filt.update(filt.predict(b, 0.25, rng), step, rng)
            return b

        return run

    return Case("kushwaha2010", "bootstrap, 9 Gaussian bearings", build)


def cases() -> dict[str, Case]:
    """Every variant (and baseline) by name."""
    out = {name: _zhai_case(name) for name in ZHAI}
    out["ASIR, position fix"] = _ercan_case(False)
    out["ASIR, occlusion-aware"] = _ercan_case(True)
    out["bootstrap, 9 Gaussian bearings"] = _kushwaha_case(False)
    out["detection-function PF"] = _kushwaha_case(True)
    return out


# --------------------------------------------------------------------------------------------
# timing


def time_case(case: Case, n: int, steps: int, repeats: int) -> dict[str, float]:
    """``{"cpu": .., "wall": ..}`` seconds per step: the fastest of ``repeats`` timed runs after
    one untimed run, each run on a filter built outside the clock."""
    case.build(n, steps, 99)()  # compile, caches
    best = {"cpu": math.inf, "wall": math.inf}
    for r in range(repeats):
        run = case.build(n, steps, r)
        with _results.Clock() as c:
            run()
        best = {"cpu": min(best["cpu"], c.cpu / steps), "wall": min(best["wall"], c.wall / steps)}
    return best


def predicted_cpu(name: str, last: tuple[int, float] | None, n: int, runs: int) -> float:
    """CPU seconds that timing ``name`` at ``n`` would take (``runs`` runs of the steps), from
    the last size measured (``(N, seconds per run)``); 0 when nothing is known yet."""
    if last is None:
        return 0.0
    grow = 2 if name in QUADRATIC else 1
    return last[1] * (n / last[0]) ** grow * runs


def measure(args: argparse.Namespace) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Rows ``{variant, family, N, cpu/wall seconds per step and per particle, ops, ns_per_op,
    ratio to the baseline}`` and the skipped sizes."""
    table = cases()
    names = args.variants or list(table)
    names = [*dict.fromkeys([table[m].baseline for m in names] + names)]  # baselines first
    share = args.budget / len(names)
    rows, skipped, times = [], [], {}
    for name in names:
        last: tuple[int, float] | None = None
        for n in sorted(args.N):
            cost = predicted_cpu(name, last, n, args.repeats + 1)
            if cost > share:
                skipped.append({"variant": name, "N": n, "predicted_cpu_seconds": cost})
                continue
            t = time_case(table[name], n, args.steps, args.repeats)
            times[name, n] = t
            last = (n, t["cpu"] * args.steps)
            rows.append(_row(name, table[name], n, t, times.get((table[name].baseline, n))))
            if not args.json:
                print(_line(rows[-1]), flush=True)
    return rows, skipped


def _row(
    name: str, case: Case, n: int, t: dict[str, float], base: dict[str, float] | None
) -> dict[str, Any]:
    ops = operations(name, n)
    base_ops = operations(case.baseline, n)
    row: dict[str, Any] = {
        "variant": name,
        "family": case.family,
        "baseline": case.baseline,
        "N": n,
        "cpu_seconds_per_step": t["cpu"],
        "wall_seconds_per_step": t["wall"],
        "cpu_ns_per_particle": 1e9 * t["cpu"] / n,
        "wall_ns_per_particle": 1e9 * t["wall"] / n,
        "ops_per_particle": ops,
        "ns_per_op": 1e9 * t["cpu"] / n / ops,
        "ops_relative_to_baseline": ops / base_ops,
    }
    for clock in ("cpu", "wall"):
        row[f"{clock}_relative_to_baseline"] = (
            _results.ratio(t[clock], base[clock]) if base else None
        )
    # how far above its arithmetic: CPU ratio to the baseline over the operations' ratio (1 =
    # each operation costs what the baseline's do)
    row["above_arithmetic"] = _results.ratio(row["cpu_relative_to_baseline"], ops / base_ops)
    return row


def markdown(doc: dict[str, Any]) -> str:
    """The README's table from a results file: one line per variant, N = 10^3, 10^4, 10^5."""
    rows = [r for r in doc["results"] if "variant" in r]
    sizes = sorted({r["N"] for r in rows})
    by = {(r["variant"], r["N"]): r for r in rows}
    head = ["family", "variant", "ops/particle (N = 1e4)"]
    for n in sizes:
        head += [f"ns/particle N={n:.0e}", "x base", "x arith"]
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * 2 + "---:|" * (len(head) - 2)]
    for name in dict.fromkeys(r["variant"] for r in rows):
        first = next(r for r in rows if r["variant"] == name)
        ops = operations(name, 10_000)
        cells = [first["family"], name, f"{ops:.0f}"]
        for n in sizes:
            r = by.get((name, n))
            if r is None:
                cells += ["skipped", "", ""]
                continue
            rel = r["cpu_relative_to_baseline"]
            above = _results.ratio(rel, r["ops_relative_to_baseline"])
            cells += [
                f"{r['cpu_ns_per_particle']:.0f}",
                f"{rel:.1f}" if rel is not None else "",
                f"{above:.1f}" if above is not None else "",
            ]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def _line(r: dict[str, Any]) -> str:
    rel = r["cpu_relative_to_baseline"]
    rel_s = f"{rel:7.1f}x" if rel is not None else "      -"
    return (
        f"{r['family']:13s} {r['variant']:30s} N={r['N']:<7d} cpu {r['cpu_ns_per_particle']:9.0f}"
        f" ns/particle ({rel_s} {r['baseline']}), wall {r['wall_ns_per_particle']:9.0f};"
        f" ops {r['ops_per_particle']:9.0f} ({r['ops_relative_to_baseline']:.1f}x), "
        f"{r['ns_per_op']:.2f} ns/op"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--N", type=int, nargs="+", default=[1000, 10000, 100000])
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--variants", nargs="+", default=None, choices=list(OPS))
    ap.add_argument("--budget", type=float, default=480.0, help="CPU seconds for all timings")
    ap.add_argument("--json", action="store_true")
    _results.add_arguments(ap)
    ap.add_argument("--table", type=Path, default=None, help="print a results file as markdown")
    args = ap.parse_args(argv)
    if args.table is not None:
        print(markdown(_results.load(args.table)))
        return 0
    if args.threads is not None and args.threads < 1:
        ap.error("--threads must be >= 1")
    if min(args.N) < 1 or args.steps < 1 or args.repeats < 1:
        ap.error("--N, --steps and --repeats must be >= 1")
    run = _results.Run(argv, __file__)
    with _results.limit_threads(args.threads) as threads:
        run.threads = threads
        rows, skipped = measure(args)
    doc = [
        *rows,
        {"skipped": skipped, "steps": args.steps, "repeats": args.repeats, "budget": args.budget},
    ]
    if args.json:
        print(json.dumps(doc, default=float))
    else:
        for s in skipped:
            print(
                f"skipped {s['variant']} N={s['N']}: predicted {s['predicted_cpu_seconds']:.0f} CPU s"
            )
    run.save(_results.out_path(args, __file__), doc)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
