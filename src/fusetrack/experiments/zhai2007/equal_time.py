"""Beyond the paper, shared by the Zhai 2007 experiments: the UPF and a bootstrap filter given
the time of the paper's filter (calibrated per configuration before the runs), and the
comparison that reports them beside the paper's filters."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from ...evaluation import RunContext
from ...filters import ProposalParticleFilter
from .comparators import (
    Comparison,
    Scenario,
    calibration_note,
    compare,
    equal_time_particles,
    per_run_scores,
    sis_reference,
)

EQUAL_TIME_METHODS = ("UPF", "bootstrap equal time")
"""The particle comparators calibrated to the reference's time."""


@dataclass
class EqualTime:
    """Per configuration key: the particle counts of :data:`EQUAL_TIME_METHODS` and the target
    seconds, calibrated by :func:`~.comparators.equal_time_particles` to a reference run (fastest
    of ``repeats``) on that configuration's run-0 scenario."""

    repeats: int
    n_particles: dict[Any, dict[str, int]] = field(default_factory=dict)
    target: dict[Any, float] = field(default_factory=dict)

    @classmethod
    def for_run(cls, ctx: RunContext) -> EqualTime:
        """Two pilot repeats in a quick run, three otherwise."""
        return cls(repeats=2 if ctx.quick else 3)

    def calibrate(self, key: Any, scn: Scenario, reference: Callable[[], object]) -> dict[str, int]:
        """Calibrate the comparators on ``scn`` to ``reference()``'s time; their counts."""
        self.n_particles[key], self.target[key] = equal_time_particles(
            scn, reference, EQUAL_TIME_METHODS, repeats=self.repeats
        )
        return self.n_particles[key]

    def calibrate_sis(
        self, key: Any, scn: Scenario, make: Callable[[], ProposalParticleFilter]
    ) -> dict[str, int]:
        """:meth:`calibrate` to a fresh ``make()`` particle filter run over ``scn``."""
        return self.calibrate(key, scn, sis_reference(scn, make))

    def compare(
        self,
        per_run: pd.DataFrame,
        reference: Any,
        figure_path: Path | None,
        *,
        notes: Sequence[str],
        calibration: str = "",
        **options: Any,
    ) -> Comparison:
        """:func:`~.comparators.compare` with the calibration note (``calibration`` appended)
        and the calibrated particle counts (reported as ``n_particles`` unless given)."""
        n_particles = options.pop("n_particles", self.n_particles)
        return compare(
            per_run,
            reference,
            figure_path,
            calibration=calibration_note(self.n_particles, self.target) + calibration,
            notes=notes,
            n_particles=n_particles,
            **options,
        )

    def compare_runs(
        self,
        ctx: RunContext,
        rows: pd.DataFrame,
        by: Sequence[str],
        sq_error: str,
        reference: Any,
        *,
        notes: Sequence[str],
        **options: Any,
    ) -> Comparison:
        """:meth:`compare` of the per-run RMSE (``sqrt`` of the mean of ``rows[sq_error]`` over
        a run's steps) per ``by`` configuration, figure ``error_vs_seconds``."""
        return self.compare(
            per_run_scores(rows, by, sq_error),
            reference,
            ctx.figure_path("error_vs_seconds"),
            by=by,
            notes=notes,
            **options,
        )
