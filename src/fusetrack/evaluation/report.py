"""The files every experiment run writes: ``results.parquet``, ``summary.json`` and ``report.md``.

An experiment returns an :class:`Outcome` (tidy rows, claims, the report's markdown body); this
module writes the three files, with the cost of the run (seconds, peak memory) measured here and
the machine it was measured on (:mod:`.machine`).
"""

from __future__ import annotations

import json
import math
import os
import resource
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from fnmatch import fnmatchcase
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..core import ConfigError, invalid
from .checkpoint import CHECKPOINT_NAME, Checkpoint
from .machine import machine, machine_line
from .montecarlo import ENGINES, RunFunction, run_monte_carlo
from .options import ExperimentOptions

KINDS = ("paper", "calibration", "diagnostic", "beyond")
"""What a claim is: ``paper`` (a number, ordering or statement the paper makes), ``calibration``
(a target a free parameter was tuned to reach), ``diagnostic`` (our own check under a reading),
``beyond`` (modern baselines, beyond the paper). Tallies count ``paper`` claims only."""


def check_kind(kind: str, field: str = "kind") -> str:
    """``kind`` if it is one of :data:`KINDS`, else :class:`ConfigError` naming it."""
    if kind not in KINDS:
        raise ConfigError(invalid(field, kind, f"one of {KINDS}"))
    return kind


@dataclass(frozen=True)
class Claim:
    """One checked statement: what the paper prints, what this run measured, whether it holds,
    and its ``kind`` (one of :data:`KINDS`)."""

    id: str
    statement: str
    paper: Any
    ours: Any
    tolerance: Any
    holds: bool
    kind: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "holds", bool(self.holds))
        check_kind(self.kind, f"kind of claim {self.id!r}")


class ClaimKinds:
    """An experiment's ``claim id -> kind`` table, kept next to its claims: keys are exact ids
    or ``fnmatch`` patterns (``"C14_*"``), tried in order. It also labels the claims of old
    ``summary.json`` files written before kinds existed (``fusetrack reports tally``), which
    leaves out the ``retired`` ids: claims removed because they held by construction."""

    def __init__(self, table: Mapping[str, str], retired: Sequence[str] = ()) -> None:
        self.table = {
            pattern: check_kind(k, f"kind of {pattern!r}") for pattern, k in table.items()
        }
        self.retired = frozenset(retired)

    def kind_of(self, claim_id: str) -> str:
        """The kind of ``claim_id``: :class:`ConfigError` if no key matches or it is retired."""
        if claim_id not in self.retired:
            for pattern, kind in self.table.items():
                if claim_id == pattern or fnmatchcase(claim_id, pattern):
                    return kind
        raise ConfigError(
            invalid("claim id", claim_id, f"an id this table gives a kind: {list(self.table)}")
        )

    def claim(self, *args: Any, **kwargs: Any) -> Claim:
        """:class:`Claim` with the fields given and the kind this table gives its id."""
        claim_id = kwargs["id"] if "id" in kwargs else args[0]
        return Claim(*args, **{**kwargs, "kind": self.kind_of(claim_id)})


@dataclass
class RunContext:
    """Options of one ``fusetrack run``: the CLI builds it, the experiment reads it.

    ``extra`` holds the experiment's own options as given (``--set KEY=VALUE``, ``--config``,
    ``--measurements``; the report repeats them); ``options`` the same validated against the
    experiment's options model (:mod:`.options`), set by the registry before the run."""

    name: str
    out_dir: Path
    quick: bool = False
    runs: int | None = None
    seed: int = 0
    engine: str = "local"
    scheduler: str | None = None
    workers: int | None = None
    progress: bool | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    options: ExperimentOptions | None = None
    resume: bool = True
    """A full-size run keeps every finished Monte Carlo run in ``out_dir`` (:mod:`.checkpoint`)
    and, started again after an interruption, resumes from it; False starts afresh."""
    resumed_runs: int = field(default=0, init=False)
    _checkpoint: Checkpoint | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        self.out_dir = Path(self.out_dir)
        if self.engine not in ENGINES:
            raise ConfigError(invalid("engine", self.engine, f"one of {ENGINES}"))
        if self.runs is not None and self.runs < 1:
            raise ConfigError(invalid("runs", self.runs, "an integer >= 1"))
        if self.scheduler is not None and self.engine != "dask":
            raise ConfigError(invalid("scheduler", self.scheduler, "only with --engine dask"))

    def n_runs(self, full: int, quick: int) -> int:
        """Runs to do: ``--runs`` if given, else the paper's count (``full``) or ``quick``."""
        if self.runs is not None:
            return self.runs
        return quick if self.quick else full

    def n_workers(self) -> int:
        """Worker processes the Monte Carlo runs use: ``--workers``, else one per CPU."""
        return self.workers if self.workers is not None else (os.cpu_count() or 1)

    def checkpoint(self) -> Checkpoint | None:
        """The run's checkpoint (full-size runs only; quick runs are cheap to redo), opened once;
        with ``resume=False`` an old one is deleted first."""
        if self.quick:
            return None
        if self._checkpoint is None:
            path = self.out_dir / CHECKPOINT_NAME
            if not self.resume:
                path.unlink(missing_ok=True)
            self._checkpoint = Checkpoint(path)
        return self._checkpoint

    def monte_carlo(
        self, fn: RunFunction, configs: Sequence[Mapping[str, Any]], runs: int, desc: str = "runs"
    ) -> pd.DataFrame:
        df = run_monte_carlo(
            fn,
            configs,
            runs,
            self.seed,
            engine=self.engine,  # type: ignore[arg-type]
            workers=self.workers,
            scheduler=self.scheduler,
            progress=self.progress,
            desc=f"{self.name}: {desc}",
            checkpoint=self.checkpoint(),
        )
        self.resumed_runs += int(df.attrs.get("resumed_runs", 0))
        return df

    def discard_checkpoint(self) -> None:
        """The run's outputs are written: nothing is left to resume."""
        if self._checkpoint is not None:
            self._checkpoint.remove()

    def figure_path(self, stem: str) -> Path:
        self.out_dir.mkdir(parents=True, exist_ok=True)
        return self.out_dir / f"{stem}.png"


@dataclass
class Outcome:
    """What an experiment hands back: tidy rows, claims, and the report's markdown body."""

    results: pd.DataFrame
    claims: list[Claim]
    report: str
    runs: int
    title: str = ""
    beyond_the_paper: dict[str, Any] = field(default_factory=dict)  # summary.json, not claims


def _jsonable(v: Any) -> Any:
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return _jsonable(v.tolist())
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return v


def peak_memory_mb() -> float:
    """Peak resident memory of this process and of its finished child processes, in MiB."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return max(own, children) / 1024.0


def claims_table(claims: Sequence[Claim]) -> str:
    """Markdown table of claims, with each claim's kind ("–" in the paper column: a check of
    ours with no paper value, e.g. that a posterior mean has converged)."""
    lines = [
        "| id | kind | statement | paper | ours | tolerance | holds |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in claims:
        ours = f"{c.ours:.4g}" if isinstance(c.ours, float) else str(c.ours)
        lines.append(
            f"| {c.id} | {c.kind} | {c.statement} | {'–' if c.paper is None else c.paper} "
            f"| {ours} | {c.tolerance} "
            f"| {'yes' if c.holds else '**no**'} |"
        )
    return "\n".join(lines)


def verdict_line(claims: Sequence[Claim]) -> str:
    """``"k of n paper claims hold"``, then the other kinds apart: ``"; calibration 2 of 2, ..."``."""
    parts = []
    for kind in KINDS:
        of_kind = [c for c in claims if c.kind == kind]
        held = sum(c.holds for c in of_kind)
        if kind == "paper":
            parts.append(f"{held} of {len(of_kind)} paper claims hold")
        elif of_kind:
            parts.append(f"{kind} {held} of {len(of_kind)}")
    return "; ".join(parts)


def _option_flags(extra: dict[str, Any]) -> str:
    """``--config`` and ``--set`` options as they were given, for the report's command line."""
    flags = [
        f" --{k} {v}" if k in ("config", "measurements") else f" --set {k}={v}"
        for k, v in extra.items()
    ]
    return "".join(flags)


def write_outputs(
    ctx: RunContext, outcome: Outcome, seconds: float, memory_mb: float
) -> dict[str, Any]:
    """Write ``results.parquet``, ``summary.json`` and ``report.md`` into ``ctx.out_dir``."""
    out = ctx.out_dir
    out.mkdir(parents=True, exist_ok=True)
    df = outcome.results.copy()
    for col in df.columns:  # Parquet needs one type per column
        if df[col].dtype == object:
            df[col] = df[col].map(
                lambda v: v if v is None or isinstance(v, str) else json.dumps(_jsonable(v))
            )
    df.to_parquet(out / "results.parquet", index=False)
    facts = machine()
    summary = {
        "experiment": ctx.name,
        "claims": [_jsonable(asdict(c)) for c in outcome.claims],
        "runs": outcome.runs,
        "seed": ctx.seed,
        "seconds": round(seconds, 3),
        "workers": ctx.n_workers(),
        "peak_memory_mb": round(memory_mb, 1),
        "machine": facts,
        "quick": ctx.quick,
        "engine": ctx.engine,
    }
    if ctx.resumed_runs:
        summary["resumed_runs"] = ctx.resumed_runs
    if outcome.beyond_the_paper:
        summary["beyond_the_paper"] = _jsonable(outcome.beyond_the_paper)
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    header = [
        f"# {outcome.title or ctx.name}",
        "",
        f"`fusetrack run {ctx.name}{' --quick' if ctx.quick else ''} --runs {outcome.runs} --seed {ctx.seed}"
        f" --engine {ctx.engine} --workers {ctx.n_workers()}{_option_flags(ctx.extra)}` — {seconds:.1f} s on {machine_line(facts)}, peak memory {memory_mb:.0f} MiB"
        f"{' (quick run: fewer runs, wider tolerances)' if ctx.quick else ''}.",
        "",
        *(
            [
                f"Resumed: {ctx.resumed_runs} Monte Carlo runs came from the checkpoint of an "
                "earlier, interrupted invocation of the same code; the seconds above count this "
                "invocation only.",
                "",
            ]
            if ctx.resumed_runs
            else []
        ),
        f"## Claims ({verdict_line(outcome.claims)})",
        "",
        claims_table(outcome.claims),
        "",
    ]
    (out / "report.md").write_text("\n".join(header) + "\n" + outcome.report.strip() + "\n")
    ctx.discard_checkpoint()
    return summary
