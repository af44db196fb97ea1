"""Scores of one method on one run: GOSPA and its decomposition, OSPA(2), CLEAR MOT, ghost tracks."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ...core import Track
from ...evaluation import clear_mot, gospa_over_time, ospa2
from .scenario import Array, Truth

POSITION = (0, 1)


def estimate_sets(tracks: Sequence[Track], times: Array) -> list[Array]:
    """The tracks' positions ``(n, 2)`` at each of ``times`` (a track counts where it has an
    estimate at that time)."""
    out = [[] for _ in times]  # type: list[list[Array]]
    for tr in tracks:
        k = np.searchsorted(times, tr.times - 1e-6)
        ok = (k < times.size) & (np.abs(times[np.minimum(k, times.size - 1)] - tr.times) < 1e-6)
        for kk, x in zip(k[ok], tr.means[ok, :2]):
            out[int(kk)].append(x)
    return [np.array(o).reshape(-1, 2) for o in out]


def ghost_tracks(tracks: Sequence[Track], truth: Truth, radius: float) -> int:
    """Tracks whose median distance to the nearest target present is above ``radius`` (they
    follow ghosts or clutter, not a target)."""
    count = 0
    for tr in tracks:
        dists = []
        for t, x in zip(tr.times, tr.means[:, :2]):
            k = int(np.argmin(np.abs(truth.times - t)))
            present = truth.present(k)
            dists.append(np.min(np.linalg.norm(present - x, axis=1)) if len(present) else np.inf)
        count += bool(np.median(dists) > radius)
    return count


def score(tracks: Sequence[Track], truth: Truth, c: float, threshold: float) -> dict[str, Any]:
    """Every metric of one method on one run (time-averaged GOSPA components, ``p = 2``,
    ``alpha = 2``; OSPA(2) with ``p = 1``; CLEAR MOT at ``threshold``)."""
    est = estimate_sets(tracks, truth.times)
    g = gospa_over_time(est, [truth.positions[k] for k in range(truth.times.size)], c=c)
    truth_tracks = truth.tracks()
    mot = clear_mot(
        list(tracks), truth_tracks, threshold=threshold, index=POSITION, truth_index=POSITION
    )
    o2 = (
        ospa2(list(tracks), truth_tracks, c=c, index=POSITION, truth_index=POSITION)
        if tracks
        else c
    )
    return {
        "gospa": g.run_distance,
        "localisation": float(g.localisation.mean()),
        "missed": float(g.missed.mean()),
        "false": float(g.false.mean()),
        "ospa2": float(o2),
        "id_switches": mot.id_switches,
        "mota": mot.mota,
        "n_tracks": len(tracks),
        "ghost_tracks": ghost_tracks(tracks, truth, threshold),
        "gospa_t": g.distance.tolist(),
    }
