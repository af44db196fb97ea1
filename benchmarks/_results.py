"""What every benchmark script shares: ``--threads``, both clocks, the results file and its
metadata, and the agreement check that decides whether a ratio may be called a speed-up.

``--threads N`` gives every library the same number of threads: BLAS and OpenMP through
``threadpoolctl.threadpool_limits(N)`` (NumPy's / SciPy's BLAS used by Stone Soup, FilterPy,
``particles`` and fusetrack alike) and Numba's parallel loops through ``numba.set_num_threads(N)``
(fusetrack's threaded kernels, the limit reference; fusetrack's per-run normal draws use at most
``numba.get_num_threads()`` threads too). Without ``--threads`` each script keeps its earlier
setting: BLAS on one thread (a threaded ``(N, 4) @ (4, 4)`` product is pathologically slow on a
loaded machine) and Numba at its default (one thread per core). The setting in force is written
into the results' metadata either way.

Results file (``--save`` -> ``benchmarks/results/<script>.json``, or ``--out PATH``)::

    {"metadata": {date, machine, load, versions, threads, command, git}, "results": [...]}

one file per run; ``report.py`` builds ``REPORT.md`` from these files only.

Agreement (:func:`agree_monte_carlo`, :func:`agree_exact`): two libraries computing the same
filter agree when ``|mean_a - mean_b| <= q sqrt(se_a^2 + se_b^2)`` (Monte Carlo scores: RMSE over
seeds, GOSPA over seeds), ``q`` the two-sided 99.73 % quantile of Student's t with the
Welch-Satterthwaite degrees of freedom of the two standard errors: the normal's 3 (3 combined
standard errors) for many runs, larger for few (6.4 for 3 runs each, 3.4 for 10 seeds each), so
that standard errors estimated from a handful of runs do not raise false alarms; or, for
deterministic filters, when their outputs differ by at most ``1e-9``. A configuration that does
not agree is stored with ``"agree": false`` and no speed-up.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.metadata as md
import json
import math
import os
import platform
import shlex
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from fusetrack.evaluation.machine import machine

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
SE_FACTOR = 3.0  # libraries disagree when |difference| > 3 combined standard errors ...
SE_LEVEL = 0.0027  # ... or the t quantile of the same two-sided level with few runs
EXACT_TOL = 1e-9  # deterministic filters: outputs equal to 1e-9
PEERS = ("numpy", "numba", "scipy", "stonesoup", "filterpy", "particles", "fusetrack")


# --------------------------------------------------------------------------------------------
# command line


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """``--threads N`` and ``--save`` / ``--out PATH`` (see the module docstring)."""
    ap.add_argument(
        "--threads",
        type=int,
        default=None,
        help="threads for every library: BLAS/OpenMP (threadpoolctl) and Numba\n"
        "(numba.set_num_threads); default: BLAS 1 thread, Numba its default",
    )
    ap.add_argument(
        "--save",
        action="store_true",
        help="write {metadata, results} to benchmarks/results/<script>.json",
    )
    ap.add_argument("--out", type=Path, default=None, help="write {metadata, results} here")


def out_path(args: argparse.Namespace, script: str) -> Path | None:
    """Where ``--save`` / ``--out`` asks the results to go (``None``: nowhere)."""
    if getattr(args, "out", None) is not None:
        return Path(args.out)
    if getattr(args, "save", False):
        return RESULTS / f"{Path(script).stem}.json"
    return None


# --------------------------------------------------------------------------------------------
# threads


@contextmanager
def limit_threads(threads: int | None, default_blas: int | None = 1) -> Iterator[dict[str, Any]]:
    """BLAS/OpenMP and Numba limited to ``threads`` inside the block (``None``: BLAS to
    ``default_blas``, ``None`` there meaning untouched, and Numba left at its default). Yields
    the setting as recorded in the metadata."""
    from threadpoolctl import threadpool_limits

    if threads is not None and threads < 1:
        raise ValueError(f"--threads must be >= 1, got {threads}")
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # as fusetrack.filters.fused does
    blas = threads if threads is not None else default_blas
    numba_before = None
    if threads is not None:
        import numba

        numba_before = numba.get_num_threads()
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))  # type: ignore[attr-defined]
    try:
        if blas is None:
            yield thread_setting(threads)
        else:
            with threadpool_limits(limits=blas):
                yield thread_setting(threads)
    finally:
        if numba_before is not None:
            import numba

            numba.set_num_threads(numba_before)


def thread_setting(requested: int | None) -> dict[str, Any]:
    """The threads in force: what ``--threads`` asked, Numba's count, each thread pool's."""
    from threadpoolctl import threadpool_info

    out: dict[str, Any] = {"requested": requested}
    if "numba" in sys.modules:
        import numba

        out["numba"] = numba.get_num_threads()
    out["pools"] = sorted(
        {(p.get("user_api", "?"), p.get("internal_api", "?"), p["num_threads"])
         for p in threadpool_info()}
    )  # fmt: skip
    return out


# --------------------------------------------------------------------------------------------
# clocks


class Clock:
    """Wall (``perf_counter``) and CPU (``process_time``: every thread of the process) seconds
    of one block: ``with Clock() as c: ...; c.wall, c.cpu``."""

    wall: float
    cpu: float

    def __enter__(self) -> Clock:
        self._w, self._c = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc: object) -> None:
        self.wall = time.perf_counter() - self._w
        self.cpu = time.process_time() - self._c


def timed(fn: Callable[[], object]) -> tuple[float, float]:
    """``(wall, cpu)`` seconds of one call of ``fn``."""
    with Clock() as c:
        fn()
    return c.wall, c.cpu


def repeat(fn: Callable[[], object], repeats: int, stat: str = "min") -> dict[str, float]:
    """``{"wall": .., "cpu": ..}`` seconds of ``repeats`` calls of ``fn``, each clock's minimum
    (``stat="min"``) or median (``"median"``) over the calls."""
    import statistics

    calls = [timed(fn) for _ in range(max(1, repeats))]
    pick = min if stat == "min" else statistics.median
    return {"wall": pick(c[0] for c in calls), "cpu": pick(c[1] for c in calls)}


def ratio(num: float | None, den: float | None) -> float | None:
    """``num / den``, ``None`` when either is missing or ``den`` is 0."""
    if num is None or den is None or den == 0 or not math.isfinite(num * den):
        return None
    return num / den


# --------------------------------------------------------------------------------------------
# agreement


def mean_se(values: Sequence[float]) -> tuple[float, float | None]:
    """Mean and standard error of the mean (``None`` with fewer than two values)."""
    v = [float(x) for x in values]
    m = sum(v) / len(v)
    if len(v) < 2:
        return m, None
    var = sum((x - m) ** 2 for x in v) / (len(v) - 1)
    return m, math.sqrt(var / len(v))


def agree_monte_carlo(
    mean_a: float,
    se_a: float | None,
    mean_b: float,
    se_b: float | None,
    n_a: int | None = None,
    n_b: int | None = None,
) -> dict[str, Any]:
    """``|mean_a - mean_b| <= q sqrt(se_a^2 + se_b^2)``, ``q`` from :func:`t_factor` given the
    numbers of runs ``n_a``, ``n_b`` (3 without them). A missing standard error borrows the
    other's (the same filter has the same spread over seeds); both missing or a non-finite
    mean: not checked (``"agree": None``)."""
    diff = mean_a - mean_b
    if se_a is None and se_b is not None:
        se_a, n_a = se_b, n_b
    if se_b is None and se_a is not None:
        se_b, n_b = se_a, n_a
    if se_a is None or se_b is None or not math.isfinite(diff):
        return {"difference": diff if math.isfinite(diff) else None, "se": None, "agree": None}
    se = math.sqrt(se_a**2 + se_b**2)
    if not math.isfinite(se):
        return {"difference": diff, "se": None, "agree": None}
    q = t_factor(se_a, se_b, n_a, n_b)
    return {"difference": diff, "se": se, "factor": q, "agree": bool(abs(diff) <= q * se)}


def t_factor(se_a: float, se_b: float, n_a: int | None, n_b: int | None) -> float:
    """The two-sided ``1 - SE_LEVEL`` quantile of Student's t with the Welch-Satterthwaite
    degrees of freedom ``(va + vb)^2 / (va^2 / (n_a - 1) + vb^2 / (n_b - 1))``, ``v = se^2``
    (Welch 1947); ``SE_FACTOR`` (3) when the numbers of runs are not known."""
    if n_a is None or n_b is None or n_a < 2 or n_b < 2:
        return SE_FACTOR
    va, vb = se_a**2, se_b**2
    den = va**2 / (n_a - 1) + vb**2 / (n_b - 1)
    if den == 0.0:
        return SE_FACTOR  # both spreads zero: any difference disagrees
    from scipy.stats import t

    dof = (va + vb) ** 2 / den
    return float(t.ppf(1.0 - SE_LEVEL / 2, dof))


def agree_exact(max_abs_diff: float, tol: float = EXACT_TOL) -> bool:
    """Deterministic filters: the largest absolute difference of their outputs is ``<= tol``."""
    return bool(math.isfinite(max_abs_diff) and max_abs_diff <= tol)


def all_agree(flags: Sequence[bool | None]) -> bool | None:
    """``False`` if any check failed, else ``True`` if any was made, else ``None``."""
    if any(f is False for f in flags):
        return False
    return True if any(f is True for f in flags) else None


# --------------------------------------------------------------------------------------------
# metadata and the results file


def versions(names: Sequence[str] = PEERS) -> dict[str, str]:
    """Python and the version of each of ``names`` that this process has imported."""
    out = {"python": platform.python_version()}
    for name in names:
        if name in sys.modules:
            try:
                out[name] = md.version(name)
            except md.PackageNotFoundError:
                out[name] = str(getattr(sys.modules[name], "__version__", "unknown"))
    return out


def _git() -> dict[str, Any] | None:
    try:
        head = subprocess.run(
            ["git", "-C", str(HERE), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
        )
        dirty = subprocess.run(
            ["git", "-C", str(HERE), "status", "--porcelain", "--", "../src", "."],
            capture_output=True, text=True, timeout=10,
        )  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return None
    if head.returncode != 0:
        return None
    return {"commit": head.stdout.strip(), "dirty": bool(dirty.stdout.strip())}


class Run:
    """One invocation of a benchmark: created at the start (date, load), saved at the end."""

    def __init__(self, argv: Sequence[str] | None = None, script: str | None = None) -> None:
        """``argv``: the arguments given to ``main`` (``None``: ``sys.argv``); ``script``: the
        script's path, put in front of ``argv`` in the recorded command line."""
        self.started = datetime.datetime.now(datetime.UTC)
        self.load_start = os.getloadavg()
        if argv is None:
            argv = sys.argv
        elif script is not None:
            argv = [script, *argv]
        self.argv = [_relative(a) for a in argv]
        self.threads: dict[str, Any] = {}

    def metadata(self) -> dict[str, Any]:
        """Date, machine, load at start and end, versions, threads, command line, git commit."""
        cmd = ["python", *self.argv] if self.argv else []
        return {
            "date": self.started.strftime("%Y-%m-%dT%H:%M:%SZ"),
            "seconds": round(
                (datetime.datetime.now(datetime.UTC) - self.started).total_seconds(), 1
            ),
            "machine": machine(),
            "load": {"start": list(self.load_start), "end": list(os.getloadavg())},
            "versions": versions(),
            "threads": self.threads,
            "command": shlex.join(cmd),
            "git": _git(),
        }

    def save(self, path: Path | None, results: list[dict[str, Any]]) -> Path | None:
        """Write ``{metadata, results}`` to ``path`` (nothing when ``None``)."""
        if path is None:
            return None
        path.parent.mkdir(parents=True, exist_ok=True)
        doc = {"metadata": self.metadata(), "results": results}
        path.write_text(json.dumps(doc, indent=1, default=_jsonable, allow_nan=True) + "\n")
        print(f"wrote {path}", file=sys.stderr, flush=True)
        return path


def measured(
    args: argparse.Namespace,
    script: str,
    measure: Callable[[], list[dict[str, Any]]],
    default_blas: int | None = None,
) -> list[dict[str, Any]]:
    """Run ``measure`` under the threads ``--threads`` asks for (:func:`limit_threads`), save its
    results where ``--save`` / ``--out`` says (:class:`Run`) and return them: the harness of a
    benchmark script's ``main``."""
    run = Run()
    with limit_threads(args.threads, default_blas=default_blas) as threads:
        run.threads = threads
        out = measure()
    run.save(out_path(args, script), out)
    return out


def _relative(arg: str) -> str:
    """A path inside the repository as ``benchmarks/...``; anything else unchanged."""
    try:
        return str(Path(arg).resolve().relative_to(HERE.parent)) if arg.endswith(".py") else arg
    except ValueError:
        return arg


def _jsonable(x: object) -> object:
    if hasattr(x, "tolist"):
        return x.tolist()
    if isinstance(x, Path):
        return str(x)
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")


def load(path: Path) -> dict[str, Any]:
    """A results file: ``{metadata, results}``; a JSON-lines file of rows (the multi-target
    benchmark's earlier runs) becomes ``{"metadata": {"source": path}, "results": rows}``."""
    text = path.read_text()
    if path.suffix == ".jsonl":
        rows = [json.loads(line) for line in text.splitlines() if line.strip()]
        return {"metadata": {"source": path.name}, "results": rows}
    doc = json.loads(text)
    if isinstance(doc, dict) and "results" in doc and "metadata" in doc:
        return doc
    if isinstance(doc, dict) and isinstance(doc.get("metadata"), dict):  # service_load.py
        meta = {"source": path.name, **doc["metadata"]}
        return {"metadata": meta, "results": [{k: v for k, v in doc.items() if k != "metadata"}]}
    return {"metadata": {"source": path.name}, "results": doc if isinstance(doc, list) else [doc]}
