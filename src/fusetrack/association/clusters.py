"""Clusters of one scan: connected components of the gate graph (Fortmann, Bar-Shalom & Scheffe
1983, "validation matrix" clustering).

Tracks and measurements are the nodes of a bipartite graph with an edge where a measurement is
inside a track's gate. Joint events of different components are independent, so association
probabilities factor over components and each one can be computed alone.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

IntArray = NDArray[np.int64]

_DENSE_TRACKS = 32  # up to this many tracks: boolean matrix products, not a sparse graph


def gate_clusters(gated: NDArray[np.bool_]) -> list[tuple[IntArray, IntArray]]:
    """``[(track rows, measurement columns), ...]`` of the gate matrix ``gated`` ``(T, M)``, one
    entry per connected component that holds at least one track, in order of its first track.
    Measurements gated by no track belong to no cluster."""
    t, m = gated.shape
    if t == 0:
        return []
    if t <= _DENSE_TRACKS:
        return _dense_clusters(gated)
    rows, cols = np.nonzero(gated)
    graph = coo_matrix((np.ones(rows.size), (rows, t + cols)), shape=(t + m, t + m))
    _, labels = connected_components(graph, directed=False)
    # every label's tracks and measurements in ascending order, in one sort
    track_groups = _groups(labels[:t], t + m)
    meas_groups = _groups(labels[t:], t + m)
    empty = np.zeros(0, np.int64)
    return [
        (track_groups[label], meas_groups.get(label, empty))
        for label in dict.fromkeys(labels[:t].tolist())  # first-seen order of the tracks
    ]


def _groups(labels: NDArray[np.int_], n_labels: int) -> dict[int, IntArray]:
    """``{label: the ascending indices with that label}`` (labels in ``[0, n_labels)``)."""
    order = np.argsort(labels, kind="stable").astype(np.int64)
    counts = np.bincount(labels, minlength=n_labels)
    present = np.flatnonzero(counts)
    if not present.size:
        return {}
    parts = np.split(order, np.cumsum(counts[present])[:-1])
    return dict(zip(present.tolist(), parts, strict=True))


def _dense_clusters(gated: NDArray[np.bool_]) -> list[tuple[IntArray, IntArray]]:
    """:func:`gate_clusters` of a few tracks: the tracks that share a measurement are
    neighbours (``G G^T``), and squaring the neighbour matrix until it stops growing gives
    every track the tracks it reaches; a cluster is named by its first track."""
    g = gated.astype(np.int64)
    reach = (g @ g.T) > 0
    np.fill_diagonal(reach, True)
    while True:
        wider = (reach.astype(np.int64) @ reach.astype(np.int64)) > 0
        if np.array_equal(wider, reach):
            break
        reach = wider
    first = np.argmax(reach, axis=1)  # each track's smallest reachable track
    return [
        (
            np.flatnonzero(reach[label]).astype(np.int64),
            np.flatnonzero(gated[reach[label]].any(axis=0)).astype(np.int64),
        )
        for label in dict.fromkeys(first.tolist())
    ]
