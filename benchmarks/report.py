"""Scaling curves of fusetrack and its peers; writes ``benchmarks/REPORT.md`` and its PNG plots.

    python benchmarks/report.py [--quick] [--out benchmarks]

Runs, each as one round-robin benchmark (the scripts beside this one, ``--json``):

1. time per step versus the number of particles N = 1e2 .. 1e6 (``pf_bearing.py``): fusetrack,
   the hand-fused limit reference, plain NumPy, ``particles`` and Stone Soup (a library whose
   estimated step exceeds the budget is skipped at larger N);
2. time per step versus the number of bearing sensors, 1 .. 64, at N = 1e4 (fusetrack, the limit
   reference and plain NumPy, the same filter with S sensors on a circle);
3. time per step versus the number of batched runs R at N = 1000 (``batched_runs.py``):
   fusetrack's batch against R separate fusetrack runs;
4. 1000 EKF / UKF tracks as one batch versus FilterPy (``kalman_batch.py``);
5. a cProfile of one fusetrack run at N = 1e6 (where the time goes).

The numbers in REPORT.md's tables are those of this run; the prose around them was written from
the run committed with it and says so. Timings: medians, round-robin, BLAS one thread, the load
average beside each figure.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def _json_lines(script: str, *args: str) -> list[dict]:
    out = subprocess.run(
        [sys.executable, str(HERE / script), *args, "--json"],
        capture_output=True,
        text=True,
        check=True,
    )
    return [json.loads(line) for line in out.stdout.splitlines() if line.strip()]


# --------------------------------------------------------------------------------------------
# 2. sensors sweep (the pf_bearing filter with S sensors on a circle)


def sensors_sweep(counts: list[int], n: int, steps: int, repeats: int) -> list[dict]:
    from threadpoolctl import threadpool_limits

    from _limit_reference import LimitReferencePF
    from _scenario import make_scenario
    from pf_bearing import FusetrackPF, NumpyPF

    base = make_scenario(steps=max(steps, 10))
    rows = []
    with threadpool_limits(1):
        for s_count in counts:
            ang = np.linspace(0.0, 2.0 * np.pi, s_count, endpoint=False)
            sensors = np.stack([200 + 400 * np.cos(ang), 100 + 400 * np.sin(ang)], axis=-1)
            d = base.truth[1:, None, :2] - sensors[None]
            rng = np.random.default_rng(s_count)
            z = np.arctan2(d[..., 1], d[..., 0]) + base.sigma * rng.standard_normal(d.shape[:2])
            z = (z + np.pi) % (2 * np.pi) - np.pi
            ids = tuple(f"s{i}" for i in range(s_count))
            scn = base.__class__(
                base.steps, base.dt, base.q, base.sigma, sensors, ids,
                base.prior_mean, base.prior_cov, base.truth, z,
            )  # fmt: skip
            runners = {
                "fusetrack": FusetrackPF(scn, n),
                "limit_reference": LimitReferencePF(scn, n),
                "numpy": NumpyPF(scn, n),
            }
            for r in runners.values():
                r.run(99, 2)
            times: dict[str, list[float]] = {k: [] for k in runners}
            for rep in range(repeats):
                for k, r in runners.items():
                    t0 = time.perf_counter()
                    r.run(rep, steps)
                    times[k].append((time.perf_counter() - t0) / steps)
            rows.append(
                {
                    "sensors": s_count,
                    "seconds_per_step": {k: statistics.median(v) for k, v in times.items()},
                    "load": os.getloadavg()[0],
                }
            )
            print(json.dumps(rows[-1]), flush=True)
    return rows


# --------------------------------------------------------------------------------------------
# 5. profile


def profile_fusetrack(n: int, steps: int) -> str:
    from threadpoolctl import threadpool_limits

    from _scenario import make_scenario
    from pf_bearing import FusetrackPF

    scn = make_scenario()
    with threadpool_limits(1):
        r = FusetrackPF(scn, n)
        r.run(99, 2)
        prof = cProfile.Profile(time.process_time)
        prof.enable()
        r.run(1, steps)
        prof.disable()
    buf = io.StringIO()
    pstats.Stats(prof, stream=buf).sort_stats("tottime").print_stats(14)
    lines = [ln for ln in buf.getvalue().splitlines() if ln.strip()]
    start = next(i for i, ln in enumerate(lines) if "ncalls" in ln)
    head = next(ln for ln in lines if "function calls" in ln)
    return "\n".join([head.strip(), *lines[start:]]).replace(str(HERE.parent) + "/", "")


# --------------------------------------------------------------------------------------------
# plots and the report


def _plot(path: Path, xs: dict[str, list], ys: dict[str, list], xlabel: str, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for lib in ys:
        pts = [(x, y) for x, y in zip(xs[lib], ys[lib]) if y is not None]
        if pts:
            ax.loglog(*zip(*pts), marker="o", label=lib)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("seconds per step (median, wall clock)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _fmt(t: float | None) -> str:
    if t is None:
        return "skipped"
    return f"{t * 1e3:.3g} ms" if t < 1 else f"{t:.3g} s"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small sizes (a smoke run)")
    ap.add_argument("--out", type=Path, default=HERE)
    args = ap.parse_args(argv)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    q = args.quick
    t_start = time.time()
    load0 = os.getloadavg()

    n_list = ["100", "1000", "10000"] if q else ["100", "1000", "10000", "100000", "1000000"]
    pf_rows = _json_lines(
        "pf_bearing.py", "--N", *n_list, "--steps", "5" if q else "10",
        "--repeats", "1" if q else "3", "--budget", "0.5" if q else "5",
        "--max-seconds", "10" if q else "40",
    )  # fmt: skip
    print("pf_bearing done", flush=True)
    sensor_counts = [1, 4, 16] if q else [1, 2, 4, 8, 16, 32, 64]
    sens_rows = sensors_sweep(sensor_counts, 1000 if q else 10_000, 3 if q else 10, 1 if q else 3)
    run_counts = ["1", "10"] if q else ["1", "10", "50", "200"]
    batch_rows = _json_lines(
        "batched_runs.py", "--runs", *run_counts, "--N", "1000",
        "--steps", "3" if q else "10", "--repeats", "1" if q else "3",
    )  # fmt: skip
    print("batched_runs done", flush=True)
    kal_rows = _json_lines(
        "kalman_batch.py", "--tracks", "50" if q else "1000",
        "--steps", "3" if q else "10", "--repeats", "1" if q else "3",
    )  # fmt: skip
    print("kalman_batch done", flush=True)
    prof = profile_fusetrack(10_000 if q else 1_000_000, 3 if q else 10)

    libs = list(pf_rows[0]["seconds_per_step"])
    ns = [r["N"] for r in pf_rows]
    _plot(
        out / "scaling_particles.png",
        {lib: ns for lib in libs},
        {lib: [r["seconds_per_step"][lib] for r in pf_rows] for lib in libs},
        "particles N",
        "bootstrap PF, 3 bearings: time per step vs N",
    )
    slibs = list(sens_rows[0]["seconds_per_step"])
    _plot(
        out / "scaling_sensors.png",
        {lib: [r["sensors"] for r in sens_rows] for lib in slibs},
        {lib: [r["seconds_per_step"][lib] for r in sens_rows] for lib in slibs},
        "bearing sensors",
        "bootstrap PF, N = 1e4: time per step vs sensors",
    )
    _plot(
        out / "scaling_runs.png",
        {k: [r["runs"] for r in batch_rows] for k in ("separate", "batched")},
        {k: [r["seconds_per_step"][k] for r in batch_rows] for k in ("separate", "batched")},
        "Monte Carlo runs R (N = 1000 each)",
        "R runs: one batch vs separate runs",
    )

    lines = [
        "# fusetrack speed report",
        "",
        "Written by `python benchmarks/report.py` (issue 3). Every figure below is the median "
        "of round-robin timed runs in one invocation, BLAS limited to one thread, wall clock "
        "unless marked cpu; the machine is a shared 2-core VM, so the load average is printed "
        "beside each table. Numba compile time is excluded (warm-up runs) and cached on disk "
        "(`cache=True`).",
        "",
        f"Run: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime(t_start))}, "
        f"{time.time() - t_start:.0f} s; load average at start {load0[0]:.1f} "
        f"(5 min {load0[1]:.1f}), at end {os.getloadavg()[0]:.1f}; {os.cpu_count()} cores.",
        "",
        "## 1. Time per step versus N (3 bearing sensors)",
        "",
        "![time per step vs N](scaling_particles.png)",
        "",
        "| N | " + " | ".join(libs) + " | fusetrack / limit | Stone Soup / fusetrack |",
        "|---|" + "---|" * (len(libs) + 2),
    ]
    for r in pf_rows:
        s = r["seconds_per_step"]
        ft, lim, ss = s.get("fusetrack"), s.get("limit_reference"), s.get("stonesoup")
        ratio = f"{ft / lim:.2f}" if ft and lim else "-"
        ss_ratio = f"{ss / ft:.0f}x" if ft and ss else "-"
        lines.append(
            f"| {r['N']:,} | "
            + " | ".join(_fmt(s[lib]) for lib in libs)
            + f" | {ratio} | {ss_ratio} |"
        )
    lines += ["", "RMSE (m) of the first timed run:", "", "| N | " + " | ".join(libs) + " |"]
    lines.append("|---|" + "---|" * len(libs))
    for r in pf_rows:
        lines.append(
            f"| {r['N']:,} | "
            + " | ".join("-" if r["rmse"][lib] is None else f"{r['rmse'][lib]:.3f}" for lib in libs)
            + " |"
        )
    lines += [
        "",
        "## 2. Time per step versus the number of sensors (N = 1e4)" if not q else "## 2. Sensors",
        "",
        "![time per step vs sensors](scaling_sensors.png)",
        "",
        "| sensors | " + " | ".join(slibs) + " | load |",
        "|---|" + "---|" * (len(slibs) + 1),
    ]
    for r in sens_rows:
        s = r["seconds_per_step"]
        lines.append(
            f"| {r['sensors']} | " + " | ".join(_fmt(s[k]) for k in slibs) + f" | {r['load']:.1f} |"
        )
    lines += [
        "",
        "## 3. Batched Monte Carlo runs (N = 1000 particles per run)",
        "",
        "![time per step vs runs](scaling_runs.png)",
        "",
        "| runs R | separate | batched | speed-up (wall) | speed-up (cpu) | bit-identical | load |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in batch_rows:
        s = r["seconds_per_step"]
        lines.append(
            f"| {r['runs']} | {_fmt(s['separate'])} | {_fmt(s['batched'])} | "
            f"{r['speedup']:.1f}x | {r['cpu_speedup']:.1f}x | {r['bit_identical']} | "
            f"{r['load']:.1f} |"
        )
    lines += [
        "",
        "## 4. Kalman family in batch (4-D CV, range-bearing radar) versus FilterPy",
        "",
        "| filter | tracks | fusetrack | FilterPy | speed-up (wall) | speed-up (cpu) | "
        "max abs diff mean / cov | load |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in kal_rows:
        s, d = r["seconds_per_step"], r["max_abs_diff"]
        lines.append(
            f"| {r['filter'].upper()} | {r['N']} | {_fmt(s['fusetrack'])} | {_fmt(s['filterpy'])} | "
            f"{r['speedup']:.1f}x | {r['cpu_speedup']:.1f}x | {d['mean']:.1e} / {d['cov']:.1e} | "
            f"{r['load']:.1f} |"
        )
    lines += [
        "",
        "## 5. Where fusetrack's time goes (cProfile, process time, "
        f"N = {'1e4' if q else '1e6'}, one run)",
        "",
        "```",
        prof,
        "```",
        "",
    ]
    notes = HERE / "REPORT_notes.md"
    if notes.exists():
        lines += [notes.read_text()]
    (out / "REPORT.md").write_text("\n".join(lines) + "\n")
    (out / "report_data.json").write_text(
        json.dumps(
            {
                "pf_bearing": pf_rows,
                "sensors": sens_rows,
                "batched_runs": batch_rows,
                "kalman_batch": kal_rows,
            },
            indent=1,
        )
    )
    print(f"wrote {out / 'REPORT.md'}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
