"""Monte Carlo runner: a run is a pure function ``(config, seed) -> rows``; engines decide where.

The seed of run ``r`` is derived from the base seed and ``r`` alone (``SeedSequence([seed, r])``),
so every configuration sees the same random numbers in the same run (common random numbers), and
the rows are identical whatever the engine or the number of workers -- or whether some of them
were computed by an earlier, interrupted invocation and kept in a checkpoint (:mod:`.checkpoint`).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from ..core import ConfigError, invalid
from .checkpoint import Checkpoint, job_key
from .terminal import progress_bar

RunFunction = Callable[[Mapping[str, Any], int], list[dict[str, Any]]]
Engine = Literal["local", "dask"]
ENGINES = ("local", "dask")


def run_seed(base_seed: int, run: int) -> int:
    """The integer seed of Monte Carlo run ``run`` (independent streams via ``SeedSequence``)."""
    return int(
        np.random.SeedSequence([int(base_seed), int(run)]).generate_state(1, np.uint64)[0] >> 1
    )


@dataclass(frozen=True)
class _Job:
    fn: RunFunction
    config_index: int
    config: Mapping[str, Any]
    run: int
    seed: int

    def __call__(self) -> list[dict[str, Any]]:
        # One BLAS thread per run: runs are the parallel unit, and threaded BLAS on the small
        # (N, d) @ (d, d) products of a filter only oversubscribes the cores.
        with threadpool_limits(limits=1):
            rows = self.fn(self.config, self.seed)
        scalar_params = {k: v for k, v in self.config.items() if np.isscalar(v) or v is None}
        out = []
        for row in rows:
            full = {
                "config": self.config_index,
                "run": self.run,
                "seed": self.seed,
                **scalar_params,
            }
            full.update(row)
            out.append(full)
        return out


def _call(job: _Job) -> list[dict[str, Any]]:
    return job()


def _jobs(
    fn: RunFunction, configs: Sequence[Mapping[str, Any]], runs: int, seed: int
) -> list[_Job]:
    if runs < 1:
        raise ConfigError(invalid("runs", runs, "an integer >= 1"))
    if not configs:
        raise ConfigError(invalid("configs", configs, "at least one configuration"))
    return [
        _Job(fn, c, cfg, r, run_seed(seed, r)) for c, cfg in enumerate(configs) for r in range(runs)
    ]


Finished = Iterator[tuple[_Job, list[dict[str, Any]]]]
"""Each job with its rows, as the jobs finish."""


def _local(jobs: list[_Job], workers: int, bar: Any) -> Finished:
    if workers <= 1 or len(jobs) == 1:
        for job in jobs:
            rows = job()
            bar.update()
            yield job, rows
        return
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(_call, job): job for job in jobs}
        for fut in as_completed(futures):
            bar.update()
            yield futures[fut], fut.result()


def _dask(jobs: list[_Job], workers: int, scheduler: str | None, bar: Any) -> Finished:
    from distributed import Client, LocalCluster
    from distributed import as_completed as dask_completed

    cluster = None
    if scheduler is None:
        cluster = LocalCluster(
            n_workers=max(workers, 1), threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        futures = client.map(_call, jobs, pure=False)
        job_of = {fut.key: job for fut, job in zip(futures, jobs)}
        for fut in dask_completed(futures):
            bar.update()
            yield job_of[fut.key], fut.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def run_monte_carlo(
    fn: RunFunction,
    configs: Sequence[Mapping[str, Any]],
    runs: int,
    seed: int = 0,
    *,
    engine: Engine = "local",
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool | None = None,
    desc: str = "runs",
    checkpoint: Checkpoint | None = None,
) -> pd.DataFrame:
    """Run ``fn(config, seed)`` for every configuration and run; return the tidy rows.

    ``fn`` must be a module-level function (it is pickled to worker processes). Every row gets
    the columns ``config`` (index), ``run``, ``seed`` and the configuration's scalar parameters.
    Rows come back sorted by (config, run), identical for every engine and worker count.
    ``progress``: False hides it; otherwise a bar on a terminal and a plain line every few
    seconds elsewhere (:func:`.terminal.progress_bar`). ``checkpoint``: runs already in it are
    not run again, and every run that finishes is saved to it at once.
    """
    if engine not in ENGINES:
        raise ConfigError(invalid("engine", engine, f"one of {ENGINES}"))
    jobs = _jobs(fn, configs, runs, seed)
    done = checkpoint.done if checkpoint is not None else {}
    keys = {id(job): job_key(fn, job.config, job.run, job.seed) for job in jobs}
    todo = [job for job in jobs if keys[id(job)] not in done]
    chunks = {id(job): done[keys[id(job)]] for job in jobs if keys[id(job)] in done}
    if chunks:
        desc = f"{desc} ({len(chunks)} of {len(jobs)} from the checkpoint)"
    n_workers = workers if workers is not None else (os.cpu_count() or 1)
    with progress_bar(len(todo), desc, progress) as bar:
        finished = (
            _local(todo, n_workers, bar)
            if engine == "local"
            else _dask(todo, n_workers, scheduler, bar)
        )
        for job, job_rows in finished if todo else ():
            if checkpoint is not None:
                checkpoint.save(keys[id(job)], job_rows)
            chunks[id(job)] = job_rows
    # runs an earlier invocation left, not those this one saved in an earlier call
    resumed = (
        sum(keys[id(job)] in checkpoint.loaded for job in jobs) if checkpoint is not None else 0
    )
    rows = [row for job in jobs for row in chunks[id(job)]]
    if not rows:
        df = pd.DataFrame(columns=["config", "run", "seed"])
    else:
        df = pd.DataFrame(rows)
        order = [c for c in ("config", "run") if c in df.columns]
        df = df.sort_values(order, kind="stable").reset_index(drop=True)
    df.attrs["resumed_runs"] = resumed  # runs taken from the checkpoint, not run again
    return df
