"""Scores of one tracker on one run of ``multitarget-benchmark``: ``multitarget-bearings``'
:func:`.scoring.score` (time-averaged GOSPA and its parts, OSPA(2), MOTA, identity switches),
plus CLEAR MOT's MOTP and fragmentations, and the series over scans: GOSPA's localisation /
missed / false parts and the number of tracks."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ...core import Track
from ...evaluation import clear_mot, gospa_over_time
from .scenario import Truth
from .scoring import POSITION, estimate_sets, score


def benchmark_score(
    tracks: Sequence[Track], truth: Truth, c: float, threshold: float
) -> dict[str, Any]:
    """:func:`.scoring.score` and the extras of the module docstring (lists: one per scan)."""
    est = estimate_sets(tracks, truth.times)
    g = gospa_over_time(est, [truth.positions[k] for k in range(truth.times.size)], c=c)
    mot = clear_mot(
        list(tracks), truth.tracks(), threshold=threshold, index=POSITION, truth_index=POSITION
    )
    return {
        **score(tracks, truth, c, threshold),
        "motp": mot.motp,
        "fragmentations": mot.fragmentations,
        "localisation_t": g.localisation.tolist(),
        "missed_t": g.missed.tolist(),
        "false_t": g.false.tolist(),
        "count_t": [len(e) for e in est],
    }


def count_bias(
    estimated: Sequence[float], true: Sequence[float] | np.ndarray, settle: int
) -> float:
    """Mean over the scans from ``settle`` on of (estimated - true number of targets)."""
    d = np.asarray(estimated, float)[settle:] - np.asarray(true, float)[settle:]
    return float(d.mean()) if d.size else float("nan")
