"""Multi-target tracking metrics: OSPA, GOSPA, OSPA^(2), CLEAR MOT and SIAP.

Two kinds of input:

* **sets of points** at one time — ``(n, d)`` arrays, one row per object; a row with a NaN is
  no object (a filter that lost its target reports NaN). :func:`ospa`, :func:`gospa` and their
  ``*_over_time`` versions take these.
* **tracks** — sequences of :class:`~fusetrack.core.Track` (``means`` ``(T, d)``, one run per
  track) for the truth and for the tracker's output. They are laid on one time grid, the union
  of all their times (times closer than ``time_tol`` are one step); a track is present at the
  steps where it has a finite estimate. ``index`` picks the position components the distances
  use (``truth_index`` for the truth when its state is laid out differently; default ``index``).
  :func:`ospa2`, :func:`clear_mot` and :func:`siap` take these.

Distances are Euclidean throughout.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linear_sum_assignment

from ..core import ConfigError, ShapeError, Track, check_positive, invalid
from .metrics import _select

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

# --------------------------------------------------------------------------------------------
# arguments


def _check_order(p: float) -> float:
    try:
        pp = float(p)
    except (TypeError, ValueError):
        raise ConfigError(invalid("p", p, "a finite order >= 1")) from None
    if not (pp >= 1.0 and np.isfinite(pp)):
        raise ConfigError(invalid("p", p, "a finite order >= 1"))
    return pp


def _check_alpha(alpha: float) -> float:
    try:
        a = float(alpha)
    except (TypeError, ValueError):
        raise ConfigError(invalid("alpha", alpha, "a number in (0, 2]")) from None
    if not 0.0 < a <= 2.0:
        raise ConfigError(invalid("alpha", alpha, "a number in (0, 2]"))
    return a


def _check_same_length(name: str, a: Sequence[object], other: str, b: Sequence[object]) -> None:
    if len(a) != len(b):
        raise ShapeError(invalid(f"len({name})", len(a), f"{len(b)} (= len({other}))"))


# --------------------------------------------------------------------------------------------
# sets of points


def _finite_rows(points: ArrayLike, name: str) -> tuple[Array, IntArray, int]:
    """The finite rows of a set ``(n, d)``, their row numbers in it, and ``n``."""
    a = np.asarray(points, dtype=float)
    if a.size == 0:
        n = a.shape[0] if a.ndim == 2 else 0
        return a.reshape(0, a.shape[-1] if a.ndim == 2 else 0), np.zeros(0, dtype=np.int64), n
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2:
        raise ShapeError(invalid(f"{name}.shape", a.shape, "(n, d): one row per object"))
    rows = np.flatnonzero(np.all(np.isfinite(a), axis=1))  # a NaN row is no estimate
    return a[rows], rows.astype(np.int64), a.shape[0]


def _as_set(points: ArrayLike, name: str) -> Array:
    return _finite_rows(points, name)[0]


def _check_dims(X: Array, Y: Array, xname: str, yname: str) -> None:
    if X.shape[0] and Y.shape[0] and X.shape[1] != Y.shape[1]:
        raise ShapeError(invalid(f"{xname}.shape", X.shape, f"(n, {Y.shape[1]}) to match {yname}"))


def _distances(X: Array, Y: Array) -> Array:
    """Euclidean distances ``(len X, len Y)``; NaN where a row is not finite."""
    if X.shape[0] == 0 or Y.shape[0] == 0:
        return np.zeros((X.shape[0], Y.shape[0]))
    return np.sqrt(np.sum((X[:, None, :] - Y[None, :, :]) ** 2, axis=-1))


def _cutoff_assignment(D: Array, c: float, p: float) -> tuple[IntArray, IntArray, Array]:
    """Hungarian assignment minimising ``sum min(D, c)^p``; returns ``(rows, cols, cost)``."""
    cost = np.minimum(D, c) ** p  # Schuhmacher, Vo & Vo 2008: cut-off base distance
    rows, cols = linear_sum_assignment(cost)
    return rows.astype(np.int64), cols.astype(np.int64), cost


def _ospa_parts(D: Array, c: float, p: float) -> tuple[float, float]:
    """OSPA localisation and cardinality parts from the base distances ``D`` between two sets."""
    if D.shape[0] > D.shape[1]:
        D = D.T
    m, n = D.shape
    if n == 0:
        return 0.0, 0.0
    if m == 0:
        return 0.0, c
    rows, cols, cost = _cutoff_assignment(D, c, p)
    loc = (cost[rows, cols].sum() / n) ** (1.0 / p)
    card = (c**p * (n - m) / n) ** (1.0 / p)
    return float(loc), float(card)


def ospa_components(
    estimates: ArrayLike, truth: ArrayLike, *, c: float, p: float = 1.0
) -> tuple[float, float]:
    """OSPA split into localisation and cardinality parts, ``ospa^p = loc^p + card^p``.

    With ``m <= n`` the smaller and larger set sizes, ``d_c(x, y) = min(c, |x - y|)`` and the
    best assignment ``pi`` (Hungarian, :func:`scipy.optimize.linear_sum_assignment`):
    ``loc = (sum_i d_c(x_i, y_pi(i))^p / n)^(1/p)``, ``card = (c^p (n - m) / n)^(1/p)``
    (Schuhmacher, Vo & Vo 2008; the split as in Ristic, Vo, Clark & Vo 2011). Both sets empty:
    (0, 0); exactly one empty: (0, c). Rows with NaN are dropped (a NaN estimate is no estimate).
    """
    cc = check_positive("c", c)
    pp = _check_order(p)
    X = _as_set(estimates, "estimates")
    Y = _as_set(truth, "truth")
    _check_dims(X, Y, "estimates", "truth")
    return _ospa_parts(_distances(X, Y), cc, pp)


def ospa(estimates: ArrayLike, truth: ArrayLike, *, c: float, p: float = 1.0) -> float:
    """OSPA distance of order ``p``, cut-off ``c``, between finite sets ``(n, d)`` and ``(m, d)``.

    ``d_p^(c)(X, Y) = ( (1/n) (min_pi sum_{i<=m} d_c(x_i, y_pi(i))^p + c^p (n - m)) )^(1/p)`` for
    ``m <= n`` (Schuhmacher, Vo & Vo 2008); 0 when both are empty, ``c`` when one is.
    The result lies in ``[0, c]``.
    """
    loc, card = ospa_components(estimates, truth, c=c, p=p)
    pp = float(p)
    return float((loc**pp + card**pp) ** (1.0 / pp))


def ospa_over_time(
    estimates: Sequence[ArrayLike], truth: Sequence[ArrayLike], *, c: float, p: float = 1.0
) -> Array:
    """OSPA at every step of two equally long sequences of sets: ``(T,)``."""
    _check_same_length("estimates", estimates, "truth", truth)
    return np.array([ospa(x, y, c=c, p=p) for x, y in zip(estimates, truth)], dtype=float)


@dataclass(frozen=True, eq=False)
class GospaResult:
    """GOSPA at one time and its decomposition, in units of distance^p.

    ``distance**p == localisation + missed + false``. ``assignment[i]`` is the estimate row
    assigned to truth row ``i``, or -1 (missed, or a NaN truth row).
    """

    distance: float
    localisation: float
    missed: float
    false: float
    assignment: IntArray
    n_missed: int
    n_false: int


def gospa(
    estimates: ArrayLike, truth: ArrayLike, *, c: float, p: float = 2.0, alpha: float = 2.0
) -> GospaResult:
    """GOSPA distance between estimated ``(n, d)`` and true ``(m, d)`` sets.

    Rahmathullah, García-Fernández & Svensson 2017, Definition 1: with ``|X| <= |Y|``,
    ``d = (min_pi sum_i min(c, |x_i - y_pi(i)|)^p + c^p / alpha (|Y| - |X|))^(1/p)``.
    For ``alpha = 2`` (their Proposition 1) this equals
    ``(sum_{(i,j) assigned} |x_i - y_j|^p + c^p / 2 (#missed + #false))^(1/p)`` over
    assignments whose pairs are closer than ``c``: a pair at ``>= c`` counts as one missed and
    one false object, and the decomposition localisation / missed / false follows. For
    ``alpha < 2`` every pair of the optimal assignment stays assigned (at cost ``c^p`` when cut
    off) and only the cardinality difference is missed or false. Rows with NaN are no objects.
    """
    cc = check_positive("c", c)
    pp = _check_order(p)
    aa = _check_alpha(alpha)
    X, x_rows, _ = _finite_rows(estimates, "estimates")
    Y, y_rows, n_truth_rows = _finite_rows(truth, "truth")
    _check_dims(X, Y, "estimates", "truth")
    D = _distances(Y, X)  # truth rows, estimate columns
    rows, cols, cost = _cutoff_assignment(D, cc, pp)
    if aa == 2.0:
        kept = D[rows, cols] < cc
        rows, cols = rows[kept], cols[kept]
    n_missed = Y.shape[0] - rows.size
    n_false = X.shape[0] - rows.size
    loc = float(cost[rows, cols].sum())
    missed = cc**pp / aa * n_missed
    false = cc**pp / aa * n_false
    assignment = np.full(n_truth_rows, -1, dtype=np.int64)
    assignment[y_rows[rows]] = x_rows[cols]
    distance = (loc + missed + false) ** (1.0 / pp)
    return GospaResult(float(distance), loc, missed, false, assignment, n_missed, n_false)


@dataclass(frozen=True, eq=False)
class GospaSeries:
    """GOSPA at every step ``(T,)``, with its decomposition (units of distance^p)."""

    distance: Array
    localisation: Array
    missed: Array
    false: Array
    n_missed: IntArray
    n_false: IntArray
    assignments: tuple[IntArray, ...]
    p: float

    @property
    def run_distance(self) -> float:
        """GOSPA over the run, ``(mean_t d_t^p)^(1/p)`` (RMS GOSPA for ``p = 2``).

        Its p-th power is the sum of the time-averaged components:
        ``run_distance**p == localisation.mean() + missed.mean() + false.mean()``.
        """
        if self.distance.size == 0:
            return float("nan")
        return float(np.mean(self.distance**self.p) ** (1.0 / self.p))


def gospa_over_time(
    estimates: Sequence[ArrayLike],
    truth: Sequence[ArrayLike],
    *,
    c: float,
    p: float = 2.0,
    alpha: float = 2.0,
) -> GospaSeries:
    """:func:`gospa` at every step of two equally long sequences of sets."""
    _check_same_length("estimates", estimates, "truth", truth)
    res = [gospa(x, y, c=c, p=p, alpha=alpha) for x, y in zip(estimates, truth)]

    def col(name: str) -> Array:
        return np.array([getattr(r, name) for r in res], dtype=float)

    return GospaSeries(
        col("distance"),
        col("localisation"),
        col("missed"),
        col("false"),
        np.array([r.n_missed for r in res], dtype=np.int64),
        np.array([r.n_false for r in res], dtype=np.int64),
        tuple(r.assignment for r in res),
        float(p),
    )


# --------------------------------------------------------------------------------------------
# tracks on a common time grid


@dataclass(frozen=True, eq=False)
class _Grid:
    """Truth and estimated tracks laid on one time grid (NaN where a track is absent)."""

    times: Array  # (K,)
    truth: Array  # (K, n, k)
    estimates: Array  # (K, m, k)


def _track_positions(track: Track, field: str, index: Sequence[int] | None) -> Array:
    if track.means.ndim != 2:
        raise ShapeError(invalid(f"{field}.means.shape", track.means.shape, "(T, d): one run"))
    return _select(track.means, index, field)


def _time_grid(tracks: Sequence[Track], tol: float) -> Array:
    """Sorted union of the tracks' times; times within ``tol`` of the previous one merge."""
    if not tracks:
        return np.zeros(0)
    t = np.sort(np.concatenate([tr.times for tr in tracks]))
    return t[np.concatenate([[True], np.diff(t) > tol])]


def _check_tracks(tracks: object, name: str) -> None:
    """``tracks`` is a sequence of :class:`Track` with distinct ids (None: the list index)."""
    if isinstance(tracks, Track) or not isinstance(tracks, Sequence):
        raise ConfigError(invalid(name, type(tracks).__name__, "a sequence of core.Track"))
    for j, tr in enumerate(tracks):
        if not isinstance(tr, Track):
            raise ConfigError(invalid(f"{name}[{j}]", type(tr).__name__, "a fusetrack.core.Track"))
    ids = [tr.id if tr.id is not None else j for j, tr in enumerate(tracks)]
    if len(set(ids)) != len(ids):
        raise ConfigError(invalid(f"{name} ids", ids, "distinct ids (None means the list index)"))


def _lay_on_grid(
    tracks: Sequence[Track], grid: Array, index: Sequence[int] | None, name: str
) -> Array:
    """``(K, n, k)`` positions of ``tracks`` on ``grid``; NaN where a track has no estimate."""
    pos = [_track_positions(tr, f"{name}[{j}]", index) for j, tr in enumerate(tracks)]
    dims = {x.shape[1] for x in pos}
    if len(dims) > 1:
        raise ShapeError(invalid(f"{name} dimensions", sorted(dims), "one dimension for all"))
    out = np.full((grid.size, len(tracks), dims.pop() if dims else 0), np.nan)
    for j, (tr, x) in enumerate(zip(tracks, pos)):
        k = np.searchsorted(grid, tr.times, side="right") - 1
        if np.any(np.diff(k) <= 0):
            valid = "strictly increasing times, more than time_tol apart"
            raise ConfigError(invalid(f"{name}[{j}].times", tr.times, valid))
        out[k, j] = x
    return out


def _grid(
    estimates: Sequence[Track],
    truth: Sequence[Track],
    index: Sequence[int] | None,
    truth_index: Sequence[int] | None,
    time_tol: float,
) -> _Grid:
    tol = check_positive("time_tol", time_tol, allow_zero=True)
    _check_tracks(estimates, "estimates")
    _check_tracks(truth, "truth")
    grid = _time_grid([*estimates, *truth], tol)
    E = _lay_on_grid(estimates, grid, index, "estimates")
    T = _lay_on_grid(truth, grid, index if truth_index is None else truth_index, "truth")
    if E.shape[1] and T.shape[1] and E.shape[2] != T.shape[2]:
        valid = f"{T.shape[2]} components to match truth (see index / truth_index)"
        raise ShapeError(invalid("estimates position size", E.shape[2], valid))
    k = max(E.shape[2], T.shape[2])  # an empty side takes the other's dimension
    E = E if E.shape[1] else np.zeros((grid.size, 0, k))
    T = T if T.shape[1] else np.zeros((grid.size, 0, k))
    return _Grid(grid, T, E)


def _present(states: Array) -> NDArray[np.bool_]:
    return np.all(np.isfinite(states), axis=-1)


def _pair_distances(T: Array, E: Array) -> Array:
    """Distances ``(..., n, m)`` between truths ``(..., n, k)`` and estimates ``(..., m, k)``;
    ``inf`` where either is absent."""
    d = np.sqrt(np.sum((T[..., :, None, :] - E[..., None, :, :]) ** 2, axis=-1))
    return np.where(np.isfinite(d), d, np.inf)


# --------------------------------------------------------------------------------------------
# OSPA^(2)


def _track_base_distances(T: Array, E: Array, c: float) -> Array:
    """Time-averaged base distance between every true and estimated track ``(n, m)``.

    Beard, Vo & Vo 2017: ``d(x, y) = sum_{t in D_x u D_y} d_c({x(t)}, {y(t)}) /
    |D_x u D_y|``, where the OSPA between the one-or-no-point sets is ``min(c, |x(t) - y(t)|)``
    when both exist and ``c`` when only one does.
    """
    pt, pe = _present(T), _present(E)
    both = pt[:, :, None] & pe[:, None, :]
    either = pt[:, :, None] | pe[:, None, :]
    d = np.where(both, np.minimum(_pair_distances(T, E), c), c)
    total = np.where(either, d, 0.0).sum(axis=0)
    count = either.sum(axis=0)
    return np.where(count > 0, total / np.maximum(count, 1), 0.0)


def _ospa2_window(T: Array, E: Array, c: float, p: float) -> float:
    """OSPA^(2) over the steps of ``T`` ``(K, n, k)`` and ``E`` ``(K, m, k)``."""
    T = T[:, _present(T).any(axis=0)]  # a track absent from the whole window is not in it
    E = E[:, _present(E).any(axis=0)]
    loc, card = _ospa_parts(_track_base_distances(T, E, c), c, p)
    return float((loc**p + card**p) ** (1.0 / p))


def ospa2(
    estimates: Sequence[Track],
    truth: Sequence[Track],
    *,
    c: float,
    p: float = 1.0,
    index: Sequence[int] | None = None,
    truth_index: Sequence[int] | None = None,
    time_tol: float = 1e-9,
) -> float:
    """OSPA^(2) between the sets of estimated and true tracks over their whole time span.

    Beard, Vo & Vo 2017 ("OSPA(2): using the OSPA metric to evaluate multi-target tracking
    performance"): the OSPA distance of order ``p`` and cut-off ``c`` between sets of tracks,
    with the time-averaged OSPA between the tracks' states as the base distance
    (:func:`_track_base_distances`). 0 for identical sets, ``c`` when no estimated track ever
    comes within ``c`` of a true one at a common time; in ``[0, c]``.
    """
    cc = check_positive("c", c)
    pp = _check_order(p)
    g = _grid(estimates, truth, index, truth_index, time_tol)
    return _ospa2_window(g.truth, g.estimates, cc, pp)


def ospa2_over_time(
    estimates: Sequence[Track],
    truth: Sequence[Track],
    *,
    c: float,
    window: int,
    p: float = 1.0,
    index: Sequence[int] | None = None,
    truth_index: Sequence[int] | None = None,
    time_tol: float = 1e-9,
) -> tuple[Array, Array]:
    """OSPA^(2) over a sliding window of ``window`` steps ending at each step.

    Returns ``(times, values)``, both ``(K,)`` on the grid of all tracks' times; a track is in
    a window when it has an estimate in it, and early steps use the shorter window available.
    """
    cc = check_positive("c", c)
    pp = _check_order(p)
    if int(window) != window or int(window) < 1:
        raise ConfigError(invalid("window", window, "an integer >= 1 (steps)"))
    w = int(window)
    g = _grid(estimates, truth, index, truth_index, time_tol)
    values = [
        _ospa2_window(
            g.truth[max(0, k - w + 1) : k + 1], g.estimates[max(0, k - w + 1) : k + 1], cc, pp
        )
        for k in range(g.times.size)
    ]
    return g.times, np.array(values, dtype=float)


# --------------------------------------------------------------------------------------------
# CLEAR MOT


@dataclass(frozen=True, eq=False)
class ClearMotResult:
    """CLEAR MOT scores (Bernardin & Stiefelhagen 2008) and the counts behind them.

    ``mota = 1 - (misses + false_positives + id_switches) / n_truth`` and
    ``motp = total matched distance / matches`` (a distance: lower is better); NaN when
    there is no truth / no match. ``n_truth`` counts true objects over all steps.
    """

    mota: float
    motp: float
    id_switches: int
    fragmentations: int
    misses: int
    false_positives: int
    matches: int
    n_truth: int


def _match_step(D: Array, threshold: float, previous: IntArray) -> IntArray:
    """Bernardin & Stiefelhagen 2008, mapping procedure: each truth's matched estimate or -1.

    ``D`` ``(n, m)`` distances (inf where absent). Correspondences of the previous step that
    are still valid (``D <= threshold``) are kept; the remaining truths and estimates are
    matched by the Hungarian method, accepting only valid pairs.
    """
    valid = D <= threshold
    match = np.full(D.shape[0], -1, dtype=np.int64)
    for i in np.flatnonzero(previous >= 0):
        if valid[i, previous[i]]:
            match[i] = previous[i]
    used = np.zeros(D.shape[1], dtype=bool)
    used[match[match >= 0]] = True
    rows = np.flatnonzero((match < 0) & valid.any(axis=1))
    cols = np.flatnonzero(~used & valid.any(axis=0))
    if rows.size and cols.size:
        ok = valid[np.ix_(rows, cols)]
        # an invalid pair costs more than any set of valid ones: most matches, then least distance
        big = threshold * (min(rows.size, cols.size) + 1) + 1.0
        r, k = linear_sum_assignment(np.where(ok, D[np.ix_(rows, cols)], big))
        good = ok[r, k]
        match[rows[r[good]]] = cols[k[good]]
    return match


def _fragmentations(tracked: NDArray[np.bool_], present: NDArray[np.bool_]) -> int:
    """Times a true track's coverage is interrupted and later resumed (Li, Huang & Nevatia 2009)."""
    total = 0
    for i in range(present.shape[1]):
        s = tracked[present[:, i], i]
        hits = np.flatnonzero(s)
        if hits.size:
            seg = s[hits[0] : hits[-1] + 1]
            total += int(np.sum(seg[:-1] & ~seg[1:]))
    return total


def clear_mot(
    estimates: Sequence[Track],
    truth: Sequence[Track],
    *,
    threshold: float,
    index: Sequence[int] | None = None,
    truth_index: Sequence[int] | None = None,
    time_tol: float = 1e-9,
) -> ClearMotResult:
    """CLEAR MOT metrics of estimated tracks against true tracks (both with ``.id``).

    Step by step (Bernardin & Stiefelhagen 2008): a truth and an estimate may match when
    their distance is ``<= threshold``; last step's matches are kept while valid, the rest are
    matched by the Hungarian method (:func:`_match_step`). A new match of a truth whose last
    match (at any earlier step) was another track is an id switch. Unmatched truths are
    misses, unmatched estimates false positives. ``fragmentations`` counts interruptions of a
    truth's coverage that later resume. A track with ``id=None`` is known by its list index.
    """
    thr = check_positive("threshold", threshold)
    g = _grid(estimates, truth, index, truth_index, time_tol)
    n = g.truth.shape[1]
    pt, pe = _present(g.truth), _present(g.estimates)
    previous = np.full(n, -1, dtype=np.int64)
    last = np.full(n, -1, dtype=np.int64)
    tracked = np.zeros(pt.shape, dtype=bool)
    switches = matches = 0
    distance = 0.0
    for k in range(g.times.size):
        D = _pair_distances(g.truth[k], g.estimates[k])
        match = _match_step(D, thr, previous)
        hit = match >= 0
        switches += int(np.sum(hit & (match != previous) & (last >= 0) & (last != match)))
        distance += float(D[hit, match[hit]].sum())
        matches += int(hit.sum())
        last = np.where(hit, match, last)
        previous = match
        tracked[k] = hit
    n_truth = int(pt.sum())
    misses = n_truth - matches
    false_positives = int(pe.sum()) - matches
    errors = misses + false_positives + switches
    return ClearMotResult(
        mota=1.0 - errors / n_truth if n_truth else float("nan"),
        motp=distance / matches if matches else float("nan"),
        id_switches=switches,
        fragmentations=_fragmentations(tracked, pt),
        misses=misses,
        false_positives=false_positives,
        matches=matches,
        n_truth=n_truth,
    )


# --------------------------------------------------------------------------------------------
# SIAP


@dataclass(frozen=True, eq=False)
class SiapResult:
    """SIAP measures (Votruba et al. 2001; as in Stone Soup's ``SIAPMetrics``), over a run.

    ``completeness = sum JT / sum J`` (fraction of true objects tracked, ideal 1);
    ``ambiguity = sum NA / sum JT`` (tracks per tracked truth, ideal 1);
    ``spuriousness = sum (N - NA) / sum N`` (fraction of tracks on no truth, ideal 0);
    ``position_accuracy = sum |error| / sum NA`` over associated (track, truth) pairs;
    ``rate_of_track_number_change = sum_j (NU_j - 1) / sum_j TT_j`` (per second, ideal 0);
    ``longest_track_segment = sum_j TL_j / sum_j T_j`` (ideal 1). ``J``/``JT``: true objects /
    tracked true objects, ``N``/``NA``: tracks / associated tracks, at each step; ``NU_j``: the
    fewest tracks covering truth ``j``'s tracked steps, ``TT_j``: its time tracked, ``TL_j``:
    its longest time on one track, ``T_j``: its lifetime. NaN where a denominator is 0.
    """

    completeness: float
    ambiguity: float
    spuriousness: float
    position_accuracy: float
    rate_of_track_number_change: float
    longest_track_segment: float


def _ratio(num: float, den: float) -> float:
    return float(num) / float(den) if den else float("nan")


def _truth_continuity(on: NDArray[np.bool_], t: Array) -> tuple[int, float, float]:
    """``(NU, TT, TL)`` for one truth: ``on[f, j]`` says track ``j`` is on it at its step ``f``."""
    F = on.shape[0]
    end = np.tile(np.arange(F), (on.shape[1], 1)).T  # last step of the segment through (f, j)
    for f in range(F - 2, -1, -1):
        end[f] = np.where(on[f] & on[f + 1], end[f + 1], end[f])
    starts = on & np.vstack([np.ones((1, on.shape[1]), bool), ~on[:-1]])[:F]
    longest = float(np.max(t[end[starts]] - t[np.nonzero(starts)[0]], initial=0.0))
    kept = np.any(on[:-1] & on[1:], axis=1)  # same track on the truth at f and f + 1
    time_tracked = float(np.sum(np.diff(t)[kept]))
    n_tracks, f = 0, 0
    while f < F:  # greedy interval cover: the segment through f that reaches furthest
        if on[f].any():
            n_tracks += 1
            f = int(end[f, on[f]].max()) + 1
        else:
            f += 1
    return n_tracks, time_tracked, longest


def siap(
    estimates: Sequence[Track],
    truth: Sequence[Track],
    *,
    threshold: float,
    index: Sequence[int] | None = None,
    truth_index: Sequence[int] | None = None,
    time_tol: float = 1e-9,
) -> SiapResult:
    """SIAP completeness, ambiguity, spuriousness, position accuracy and continuity.

    At each step every track is associated with its nearest truth when that is within
    ``threshold`` (several tracks may share a truth: that is ambiguity). Definitions in
    :class:`SiapResult`. Unlike Stone Soup, a truth never tracked adds 0 (not -1) to the track
    number changes, and NaN (not 0 or 1) marks an empty denominator.
    """
    thr = check_positive("threshold", threshold)
    g = _grid(estimates, truth, index, truth_index, time_tol)
    D = _pair_distances(g.truth, g.estimates)  # (K, n, m)
    pt, pe = _present(g.truth), _present(g.estimates)
    if D.shape[1]:
        nearest = np.argmin(D, axis=1)  # (K, m): each track's nearest truth
        best = np.take_along_axis(D, nearest[:, None, :], axis=1)[:, 0]
    else:
        nearest, best = np.zeros(pe.shape, dtype=np.int64), np.full(pe.shape, np.inf)
    associated = pe & (best <= thr)  # (K, m)
    on = associated[:, None, :] & (nearest[:, None, :] == np.arange(D.shape[1])[None, :, None])
    n_assoc, n_tracked = int(associated.sum()), int(on.any(axis=2).sum())
    sums = np.zeros(3)  # sum (NU_j - 1)+, sum TT_j, sum TL_j
    lifetime = 0.0
    for j in range(pt.shape[1]):
        steps = np.flatnonzero(pt[:, j])
        if steps.size:
            nu, tt, tl = _truth_continuity(on[steps, j], g.times[steps])
            sums += (max(nu - 1, 0), tt, tl)
            lifetime += float(g.times[steps[-1]] - g.times[steps[0]])
    return SiapResult(
        completeness=_ratio(n_tracked, pt.sum()),
        ambiguity=_ratio(n_assoc, n_tracked),
        spuriousness=_ratio(pe.sum() - n_assoc, pe.sum()),
        position_accuracy=_ratio(float(np.sum(best[associated])), n_assoc),
        rate_of_track_number_change=_ratio(sums[0], sums[1]),
        longest_track_segment=_ratio(sums[2], lifetime),
    )
