"""Eq. 7's q of one sight line against a row of isotropic occluders (Ercan et al. 2013): the
four-pass row the kernels use (``_q_row_iso``, vectorised) against the one-triple formula
(``_q_iso``) called in one loop over the row, which is what the kernels did before 2026-12-04.

    python benchmarks/ercan2013_q_rows.py [--occluders 40] [--lines 8000] [--repeats 15]
        [--sd 1 8 32] [--lengths 7 8 31 32 ...] [--json] [--save | --out PATH]

Random sight lines (length 5-40) from a camera at the origin against ``--occluders`` occluder
means uniform over [-30, 30]^2 with prior sd ``--sd`` (cut-off 5 sd, D = 3.33). Both versions run
alternately ``--repeats`` times in one process; the result is the median ns per (sight line,
occluder) triple of each and their ratio. The two outputs are checked equal bit for bit first
(a ratio between different numbers would mean nothing). fusetrack only: no peer has Eq. 7.

``--lengths``: rows of that many occluders (sd 8) run on exactly ``n`` entries against ``n``
rounded up to whole SIMD blocks of ``_LANES`` (zero rows after the occluders); ns per sight line
of each, the first ``n`` q checked equal bit for bit, and the length the kernels pick
(``_row_length``: rounded up unless one or two are left over).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from fusetrack.world.occlusion_kernels import _LANES, _ROW_WORK, _q_iso, _q_row_iso, _row_length

HALF = 3.33 / 2


@numba.njit(cache=True)
def rows(lines, m, inv_sd, reach, out):  # pragma: no cover - jit
    n = m.shape[0]
    m1, m2 = m[:, 0].copy(), m[:, 1].copy()
    work, index = np.empty((_ROW_WORK, n)), np.empty((4, n), dtype=np.int32)
    for l in range(lines.shape[0]):
        _q_row_iso(lines[l, 0], lines[l, 1], lines[l, 2], m1, m2, inv_sd, reach, HALF, n, out[l],
                   work, index)  # fmt: skip


@numba.njit(cache=True, inline="always")
def _triples_row(u1, u2, r, m1, m2, inv_sd, reach, n, out):  # pragma: no cover - jit
    for j in range(n):  # the row loop of the kernels before 2026-12-04
        out[j] = _q_iso(u1, u2, r, m1[j], m2[j], inv_sd[j], reach[j], HALF)


@numba.njit(cache=True)
def triples(lines, m, inv_sd, reach, out):  # pragma: no cover - jit
    n = m.shape[0]
    m1, m2 = m[:, 0].copy(), m[:, 1].copy()
    for l in range(lines.shape[0]):
        _triples_row(lines[l, 0], lines[l, 1], lines[l, 2], m1, m2, inv_sd, reach, n, out[l])


@numba.njit(cache=True)
def rows_on(lines, m1, m2, inv_sd, reach, run, out):  # pragma: no cover - jit
    """The rows of ``m1 (n,)`` computed on ``run >= n`` entries (the arrays that long)."""
    work, index = np.empty((_ROW_WORK, m1.shape[0])), np.empty((4, m1.shape[0]), dtype=np.int32)
    for l in range(lines.shape[0]):
        _q_row_iso(lines[l, 0], lines[l, 1], lines[l, 2], m1, m2, inv_sd, reach, HALF, run, out[l],
                   work, index)  # fmt: skip


def measure_length(n: int, n_lines: int, repeats: int, sd: float = 8.0) -> dict[str, object]:
    """Median ns per sight line of a row of ``n`` occluders run on ``n`` and on whole blocks."""
    rng = np.random.default_rng(n)
    run = -(-n // _LANES) * _LANES  # whole SIMD blocks
    m = np.zeros((run, 2))
    m[:n] = rng.uniform(-30.0, 30.0, (n, 2))
    ang = rng.uniform(0.0, 2 * np.pi, n_lines)
    lines = np.c_[np.cos(ang), np.sin(ang), rng.uniform(5.0, 40.0, n_lines)]
    inv_sd, reach = np.zeros(run), np.zeros(run)
    inv_sd[:n], reach[:n] = 1.0 / sd, 5.0 * sd
    m1, m2 = m[:, 0].copy(), m[:, 1].copy()
    a, b = np.zeros((n_lines, run)), np.zeros((n_lines, run))
    rows_on(lines, m1, m2, inv_sd, reach, n, a)
    rows_on(lines, m1, m2, inv_sd, reach, run, b)
    if not np.array_equal(a[:, :n], b[:, :n]):
        raise SystemExit(f"{n} occluders: the padded row differs")
    times: dict[str, list[float]] = {"exact": [], "padded": []}
    for _ in range(repeats):
        for name, length, out in (("exact", n, a), ("padded", run, b)):
            t0 = time.perf_counter()
            rows_on(lines, m1, m2, inv_sd, reach, length, out)
            times[name].append((time.perf_counter() - t0) / n_lines * 1e9)
    exact, padded = float(np.median(times["exact"])), float(np.median(times["padded"]))
    return {
        "row_length": n,
        "padded_to": run,
        "kernels_run_on": int(_row_length(n)),
        "sd": sd,
        "lines": n_lines,
        "exact_ns_per_line": exact,
        "padded_ns_per_line": padded,
        "speedup": exact / padded,
    }


def measure(n_occ: int, n_lines: int, sd: float, repeats: int) -> dict[str, object]:
    """Median ns per triple of both versions at one prior sd (same inputs, alternating)."""
    rng = np.random.default_rng(0)
    m = rng.uniform(-30.0, 30.0, (n_occ, 2))
    ang = rng.uniform(0.0, 2 * np.pi, n_lines)
    lines = np.c_[np.cos(ang), np.sin(ang), rng.uniform(5.0, 40.0, n_lines)]
    inv_sd, reach = np.full(n_occ, 1.0 / sd), np.full(n_occ, 5.0 * sd)
    a, b = np.zeros((n_lines, n_occ)), np.zeros((n_lines, n_occ))
    rows(lines, m, inv_sd, reach, a)
    triples(lines, m, inv_sd, reach, b)
    if not np.array_equal(a, b):
        raise SystemExit(f"sd {sd}: the row and the one-triple formula differ")
    times: dict[str, list[float]] = {"row": [], "one_triple": []}
    for _ in range(repeats):
        for name, fn, out in (("row", rows, a), ("one_triple", triples, b)):
            t0 = time.perf_counter()
            fn(lines, m, inv_sd, reach, out)
            times[name].append((time.perf_counter() - t0) / (n_lines * n_occ) * 1e9)
    row, one = float(np.median(times["row"])), float(np.median(times["one_triple"]))
    return {
        "sd": sd,
        "occluders": n_occ,
        "lines": n_lines,
        "q_positive_share": float(np.mean(a > 0)),
        "row_ns_per_triple": row,
        "one_triple_ns_per_triple": one,
        "speedup": one / row,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--occluders", type=int, default=40)
    ap.add_argument("--lines", type=int, default=8000)
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--sd", type=float, nargs="+", default=[1.0, 8.0, 32.0])
    ap.add_argument("--lengths", type=int, nargs="*", default=[])
    ap.add_argument("--json", action="store_true")
    _results.add_arguments(ap)
    a = ap.parse_args()
    if any(n < 1 for n in a.lengths):
        raise SystemExit(f"--lengths={a.lengths} is invalid: expected row lengths >= 1")
    out = _results.measured(
        a,
        __file__,
        lambda: (
            [measure(a.occluders, a.lines, sd, a.repeats) for sd in a.sd]
            + [measure_length(n, a.lines, a.repeats) for n in a.lengths]
        ),
    )
    if a.json:
        print(json.dumps(out))
        return
    for r in out:
        if "row_length" in r:
            print(
                f"{r['row_length']:>3} occluders: {r['exact_ns_per_line']:.1f} ns per sight line "
                f"on {r['row_length']}, {r['padded_ns_per_line']:.1f} on {r['padded_to']}: "
                f"{r['speedup']:.2f}x (the kernels run on {r['kernels_run_on']})"
            )
            continue
        print(
            f"sd {r['sd']:>5g}: row {r['row_ns_per_triple']:.2f} ns, one triple "
            f"{r['one_triple_ns_per_triple']:.2f} ns per triple: {r['speedup']:.2f}x "
            f"(q > 0 in {r['q_positive_share']:.0%})"
        )


if __name__ == "__main__":
    main()
