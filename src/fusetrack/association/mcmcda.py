"""Online Markov chain Monte Carlo data association (Oh, Russell & Sastry 2009), as Kushwaha 2010 uses it.

Kushwaha 2010 (Ch. III) runs "the online version of MCMCDA" on peaks of the fused likelihood and
refers to Oh et al. for the algorithm. This module implements it as spec 003 §2.6 reconstructs it.

Model. Targets are born with rate λ_b and die with probability p_z per step, are detected with
probability p_d, false alarms have rate λ_f (both rates per step per unit area, uniform over the
field), targets move with a constant-velocity linear Gaussian model and are observed in position.
A hypothesis ω partitions the observations of a window into tracks (≥ 2 observations, at most
one per step, consecutive ones within the gate) and false alarms, and

    P(ω | Y) ∝ Π_t p_z^{z_t} (1 - p_z)^{c_t} p_d^{d_t} (1 - p_d)^{u_t} λ_b^{a_t} λ_f^{f_t}
               × Π_τ Π_i N(τ(t_{i+1}); ŷ_{t_{i+1}|t_i}(τ), B_{t_{i+1}}(τ))          (Oh et al., Eq. 8)

with z_t terminated, c_t continuing, a_t new, d_t detected, u_t = c_t + a_t - d_t undetected
tracks and f_t = n_t - d_t false alarms. Since f_t = n_t - d_t, log P is a constant plus a sum
of independent per-track scores (:meth:`MCMCDA.track_score`), which the sampler caches.

Moves (Oh et al., Sec. IV): birth/death, split/merge, extension/reduction, track update and
track switch, one of the eight chosen uniformly at every iteration. Growth (birth, extension,
update) takes uniformly one gated free observation at a time and stops with probability
``stop_prob`` once the track is long enough (or when nothing is left to take). Each move's
proposal probability q(ω'|ω) and that of its reverse are computed exactly, and the move is
accepted with min(1, P(ω'|Y) q(ω|ω') / (P(ω|Y) q(ω'|ω))): the chain samples P(ω | Y) (tested
against the enumerated posterior of a tiny problem), and the tracker reports the best hypothesis
visited (the MAP estimate), as Oh et al. do. The exact move probabilities are this module's
reconstruction (spec 003 §2.6: the dissertation omits the algorithm); they differ from the
paper's in details (e.g. a birth starts from a uniform free observation, not a uniform time).

Online: a sliding window of ``window`` steps; each new step starts the chain from the previous
best hypothesis (restricted to the window) and runs ``n_mc`` iterations; observations leaving the
window are committed to their track, and track identities persist through the overlap.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.errors import ConfigError, invalid

Obs = tuple[int, int]  # (time step, index of the observation at that step)
TrackKey = tuple[Obs, ...]
STOP: Obs = (-1, -1)  # end of a growth path (see MCMCDA._grow)


@dataclass(frozen=True)
class MCMCDAConfig:
    """Spec 003 §2.6 [C] defaults (dt 0.25 s, v̄ 20 m/s, gaps ≤ 3 steps, window 12 steps)."""

    dt: float = 0.25
    max_speed: float = 20.0
    max_gap: int = 3
    window: int = 12
    n_mc: int = 2000
    p_detect: float = 0.8
    p_terminate: float = 0.05
    birth_rate: float = 0.05  # per step, whole field
    false_alarm_rate: float = 0.1  # per step, whole field
    area: float = 35.0 * 20.0
    accel_std: float = 2.0  # m/s²
    obs_std: float = 1.0  # m
    init_speed_std: float = 10.0  # m/s, prior on a new track's velocity
    stop_prob: float = 0.3  # probability of stopping a random track extension at each step

    def __post_init__(self) -> None:
        for name in ("p_detect", "p_terminate"):
            v = getattr(self, name)
            if not 0 < v < 1:
                raise ConfigError(invalid(name, v, "a probability in (0, 1)"))
        if self.window < 2 or self.max_gap < 1:
            raise ConfigError(
                invalid("window/max_gap", (self.window, self.max_gap), "window >= 2, max_gap >= 1")
            )


def _cv_matrices(dt: float, q: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    f = np.eye(4)
    f[0, 2] = f[1, 3] = dt
    g = np.array([[dt * dt / 2, 0], [0, dt * dt / 2], [dt, 0], [0, dt]])
    return f, q * q * g @ g.T


@dataclass
class MCMCDA:
    """Online MCMCDA. Feed each step's observations with :meth:`step`; read :meth:`tracks`
    (committed, at the end) or :meth:`current_tracks` (the current estimates, after each step)."""

    config: MCMCDAConfig = field(default_factory=MCMCDAConfig)
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))
    observations: list[NDArray[np.float64]] = field(default_factory=list)
    best: list[TrackKey] = field(default_factory=list)
    ids: dict[TrackKey, int] = field(default_factory=dict)
    committed: dict[int, dict[int, int]] = field(default_factory=dict)  # id -> {t: obs index}
    accepted: int = 0
    proposed: int = 0
    _next_id: int = 0
    _forgotten: int = 0  # observations before this step were freed (forget_past)
    _cache: dict[TrackKey, float] = field(default_factory=dict)
    _gate_cache: dict[tuple[Obs, Obs], bool] = field(default_factory=dict)

    # ---- model -------------------------------------------------------------------------
    def _gate(self, a: Obs, b: Obs) -> bool:
        gap = b[0] - a[0]
        if gap < 1 or gap > self.config.max_gap:
            return False
        d = self.observations[b[0]][b[1]] - self.observations[a[0]][a[1]]
        reach = self.config.max_speed * gap * self.config.dt + 2 * self.config.obs_std
        return bool(d @ d <= reach * reach)

    def _kalman(self, track: TrackKey) -> tuple[float, list[tuple[int, NDArray[np.float64]]]]:
        """Innovation log-likelihood of a track and its filtered states at its observations."""
        ll, states = self._kalman_full(track)
        return ll, [(t, x) for t, x, _ in states]

    def _kalman_full(
        self, track: TrackKey
    ) -> tuple[float, list[tuple[int, NDArray[np.float64], NDArray[np.float64]]]]:
        """:meth:`_kalman` with the filtered covariances too: ``(ll, [(t, x, P), ...])``."""
        c = self.config
        f1, q1 = _cv_matrices(c.dt, c.accel_std)
        r = c.obs_std**2 * np.eye(2)
        y0 = self.observations[track[0][0]][track[0][1]]
        x = np.array([y0[0], y0[1], 0.0, 0.0])
        p = np.diag([c.obs_std**2, c.obs_std**2, c.init_speed_std**2, c.init_speed_std**2])
        ll = 0.0
        states = [(track[0][0], x.copy(), p.copy())]
        for prev, cur in itertools.pairwise(track):
            for _ in range(cur[0] - prev[0]):
                x = f1 @ x
                p = f1 @ p @ f1.T + q1
            y = self.observations[cur[0]][cur[1]]
            s = p[:2, :2] + r
            innov = y - x[:2]
            det = s[0, 0] * s[1, 1] - s[0, 1] * s[1, 0]
            sinv = np.array([[s[1, 1], -s[0, 1]], [-s[1, 0], s[0, 0]]]) / det
            ll += -0.5 * float(innov @ sinv @ innov) - np.log(2 * np.pi) - 0.5 * np.log(det)
            k = p[:, :2] @ sinv
            x = x + k @ innov
            p = p - k @ p[:2, :]
            states.append((cur[0], x.copy(), p.copy()))
        return ll, states

    def track_score(self, track: TrackKey, t_end: int) -> float:
        """log of this track's factor in P(ω | Y), relative to all its observations being false alarms."""
        key = (*track, (-1, t_end))
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        c = self.config
        first, last, n = track[0][0], track[-1][0], len(track)
        span = last - first + 1
        score = np.log(c.birth_rate / c.area)
        score += (span - 1) * np.log(1 - c.p_terminate)
        if last < t_end:
            score += np.log(c.p_terminate)
        score += n * np.log(c.p_detect) + (span - n) * np.log(1 - c.p_detect)
        score -= n * np.log(c.false_alarm_rate / c.area)
        score += self._kalman(track)[0]
        self._cache[key] = float(score)
        return float(score)

    # ---- moves -------------------------------------------------------------------------
    def _free(self, used: set[Obs], t: int) -> list[Obs]:
        if t < 0 or t >= len(self.observations):
            return []
        return [(t, j) for j in range(len(self.observations[t])) if (t, j) not in used]

    def _candidates(
        self, end: Obs, used: set[Obs], t_lo: int, t_hi: int, forward: bool
    ) -> list[Obs]:
        """Free observations in ``[t_lo, t_hi]`` that can follow (precede) ``end`` within the gate."""
        out = []
        for gap in range(1, self.config.max_gap + 1):
            t = end[0] + gap if forward else end[0] - gap
            if t < t_lo or t > t_hi:
                break
            out += [o for o in self._free(used, t) if self._gated(end, o, forward)]
        return out

    def _gated(self, end: Obs, o: Obs, forward: bool) -> bool:
        key = (end, o) if forward else (o, end)
        hit = self._gate_cache.get(key)
        if hit is None:
            hit = self._gate_cache[key] = self._gate(*key)
        return hit

    def _grow(
        self,
        track: list[Obs],
        used: set[Obs],
        t_lo: int,
        t_hi: int,
        forward: bool,
        min_len: int,
        path: Sequence[Obs] | None = None,
    ) -> tuple[list[Obs] | None, float]:
        """Grow ``track`` by gated free observations; returns (track, log q) or (None, -inf).

        The random growth: while the track is shorter than ``min_len`` it must take a candidate
        (none: the move fails); from ``min_len`` on it stops when there is no candidate, else
        with probability ``stop_prob``; each taken observation is uniform over the candidates.
        With ``path`` given nothing is drawn: the log probability that the growth adds exactly
        ``path`` (in growth order) and then stops is evaluated -- the reverse-move term of the
        Metropolis-Hastings ratio.
        """
        gamma = self.config.stop_prob
        track, used = list(track), set(used)
        logq = 0.0
        k = 0
        while True:
            want = None if path is None else (path[k] if k < len(path) else STOP)
            cands = self._candidates(track[-1] if forward else track[0], used, t_lo, t_hi, forward)
            if len(track) >= min_len:
                if not cands:
                    return (track, logq) if want in (None, STOP) else (None, -np.inf)
                stop = self.rng.random() < gamma if want is None else want == STOP
                if stop:
                    return track, logq + np.log(gamma)
                logq += np.log1p(-gamma)
            elif not cands or want == STOP:
                return None, -np.inf
            if want is None:
                o = cands[int(self.rng.integers(len(cands)))]
            elif want in cands:
                o = want
            else:
                return None, -np.inf
            logq -= np.log(len(cands))
            used.add(o)
            if forward:
                track.append(o)
            else:
                track.insert(0, o)
            k += 1

    def _window_free(self, used: set[Obs], t_lo: int, t_hi: int) -> list[Obs]:
        return [o for t in range(t_lo, t_hi + 1) for o in self._free(used, t)]

    def _mergeable(self, tracks: Sequence[TrackKey]) -> list[tuple[int, int]]:
        return [
            (i, j)
            for i, a in enumerate(tracks)
            for j, b in enumerate(tracks)
            if i != j and self._gated(a[-1], b[0], True)
        ]

    def _switch_options(self, a: TrackKey, b: TrackKey) -> list[tuple[int, int]]:
        return [
            (p, q)
            for p in range(len(a) - 1)
            for q in range(len(b) - 1)
            if self._gated(a[p], b[q + 1], True) and self._gated(b[q], a[p + 1], True)
        ]

    def _propose(
        self, tracks: list[TrackKey], t_lo: int, t_hi: int
    ) -> tuple[list[TrackKey], float] | None:
        """One of the eight moves, chosen uniformly; returns (proposal, log q(back)/q(forth)).

        Move pairs (each the other's reverse): birth/death, split/merge, extension/reduction,
        track update and track switch (their own reverses). ``None`` when the move cannot be
        made from ``tracks`` (the chain stays). ``t_hi`` is inclusive.
        """
        rng = self.rng
        used = {o for tr in tracks for o in tr}
        move = int(rng.integers(8))
        k = len(tracks)
        if move == 0:  # birth: a free start, grown forward; reverse: death of that track
            free = self._window_free(used, t_lo, t_hi)
            if not free:
                return None
            start = free[int(rng.integers(len(free)))]
            new, logq = self._grow([start], used | {start}, t_lo, t_hi, True, 2)
            if new is None:
                return None
            return [*tracks, tuple(new)], -np.log(k + 1) - (logq - np.log(len(free)))
        if k == 0:
            return None
        i = int(rng.integers(k))
        tr = tracks[i]
        rest = tracks[:i] + tracks[i + 1 :]
        if move == 1:  # death; reverse: birth of this track
            rest_used = used - set(tr)
            free = self._window_free(rest_used, t_lo, t_hi)
            _, logq = self._grow([tr[0]], rest_used | {tr[0]}, t_lo, t_hi, True, 2, tr[1:])
            return rest, (logq - np.log(len(free))) + np.log(k)
        if move == 2:  # split at a uniform cut of a uniform long track; reverse: merge
            long = [j for j, t in enumerate(tracks) if len(t) >= 4]
            if not long:
                return None
            tr = tracks[long[int(rng.integers(len(long)))]]
            cut = int(rng.integers(2, len(tr) - 1))
            out = [t for t in tracks if t is not tr] + [tr[:cut], tr[cut:]]
            back = -np.log(len(self._mergeable(out)))
            return out, back + np.log(len(long)) + np.log(len(tr) - 3)
        if move == 3:  # merge a uniform gated pair; reverse: split
            pairs = self._mergeable(tracks)
            if not pairs:
                return None
            ia, ib = pairs[int(rng.integers(len(pairs)))]
            merged = tracks[ia] + tracks[ib]
            out = [t for n, t in enumerate(tracks) if n not in (ia, ib)] + [merged]
            n_long = sum(len(t) >= 4 for t in out)
            return out, -np.log(n_long) - np.log(len(merged) - 3) + np.log(len(pairs))
        forward = bool(rng.random() < 0.5)
        if move == 4:  # extension by >= 1 observation; reverse: reduction of as many
            grown, logq = self._grow(list(tr), used, t_lo, t_hi, forward, len(tr) + 1)
            if grown is None:
                return None
            return [*rest, tuple(grown)], -np.log(len(grown) - 2) - logq
        if move == 5:  # reduction by r ~ U{1..len-2} at one end; reverse: extension
            if len(tr) < 3:
                return None
            r = int(rng.integers(1, len(tr) - 1))
            kept = tr[:-r] if forward else tr[r:]
            removed = tr[-r:] if forward else tr[:r][::-1]
            rest_used = used - set(removed)
            _, logq = self._grow(list(kept), rest_used, t_lo, t_hi, forward, len(kept) + 1, removed)
            return [*rest, kept], logq + np.log(len(tr) - 2)
        if (
            move == 6
        ):  # track update: keep r ~ U{1..len-1}, regrow; reverse: the same with the old tail
            r = int(rng.integers(1, len(tr)))
            base_used = used - set(tr[r:])
            grown, logq = self._grow(list(tr[:r]), base_used, t_lo, t_hi, True, 2)
            if grown is None or len(grown) <= r:
                return None
            _, back = self._grow(list(tr[:r]), base_used, t_lo, t_hi, True, 2, tr[r:])
            return [*rest, tuple(grown)], (back - np.log(len(grown) - 1)) - (
                logq - np.log(len(tr) - 1)
            )
        # move == 7: track switch of a uniform pair at a uniform crossing point
        if k < 2:
            return None
        j = int(rng.integers(k - 1))
        j = j + 1 if j >= i else j
        a, b = tracks[i], tracks[j]
        options = self._switch_options(a, b)
        if not options:
            return None
        p, q = options[int(rng.integers(len(options)))]
        na, nb = a[: p + 1] + b[q + 1 :], b[: q + 1] + a[p + 1 :]
        out = [t for n, t in enumerate(tracks) if n not in (i, j)] + [na, nb]
        return out, np.log(len(options)) - np.log(len(self._switch_options(na, nb)))

    def _total(self, tracks: Sequence[TrackKey], t_end: int) -> float:
        return sum(self.track_score(t, t_end) for t in tracks)

    def mh_step(
        self, tracks: list[TrackKey], score: float, t_lo: int, t_hi: int
    ) -> tuple[list[TrackKey], float]:
        """One Metropolis-Hastings transition on the hypotheses of steps ``t_lo..t_hi`` (inclusive).

        Accepts with ``min(1, P(ω'|Y) q(ω|ω') / (P(ω|Y) q(ω'|ω)))`` (Oh et al. 2009, Alg. 1),
        so the chain's stationary law is ``P(ω | Y)``; ``score`` is ``log P(ω | Y)`` up to a constant.
        """
        self.proposed += 1
        move = self._propose(tracks, t_lo, t_hi)
        if move is None:
            return tracks, score
        proposal, log_ratio = move
        new = self._total(proposal, t_hi)
        if np.log(self.rng.random() + 1e-300) < new - score + log_ratio:
            self.accepted += 1
            return proposal, new
        return tracks, score

    # ---- online loop -------------------------------------------------------------------
    def step(self, observations: ArrayLike) -> None:
        """Add one step's observations ``(n, 2)`` and update the MAP hypothesis of the window."""
        y = np.asarray(observations, float).reshape(-1, 2)
        y = y[np.all(np.isfinite(y), axis=1)]
        self.observations.append(y)
        t_hi = len(self.observations) - 1
        t_lo = max(0, t_hi - self.config.window + 1)
        # Observations at t_lo - 1 just left the window: commit them.
        self._commit(t_lo - 1)
        current = []
        for tr in self.best:
            kept = tuple(o for o in tr if o[0] >= t_lo)
            if len(kept) >= 2:
                current.append(kept)
                if tr in self.ids:
                    self.ids.setdefault(kept, self.ids[tr])
        current_score = self._total(current, t_hi)
        best, best_score = list(current), current_score
        for _ in range(self.config.n_mc):
            current, current_score = self.mh_step(current, current_score, t_lo, t_hi)
            if current_score > best_score:
                best, best_score = list(current), current_score
        self._assign_ids(best)
        self.best = best
        if len(self._cache) > 200_000:
            self._cache.clear()
            self._gate_cache.clear()

    def _assign_ids(self, new: list[TrackKey]) -> None:
        old = [(set(t), self.ids[t]) for t in self.best if t in self.ids]
        old += [
            (set(t), i)
            for t, i in self.ids.items()
            if t not in self.best and any(set(t) & set(n) for n in new)
        ]
        taken: set[int] = set()
        for tr in sorted(new, key=len, reverse=True):
            s = set(tr)
            overlap = sorted(
                ((len(s & o), i) for o, i in old if i not in taken and s & o), reverse=True
            )
            if overlap:
                ident = overlap[0][1]
            else:
                ident = self._next_id
                self._next_id += 1
            taken.add(ident)
            self.ids[tr] = ident
        self.ids = {t: i for t, i in self.ids.items() if t in new}

    def _commit(self, t: int) -> None:
        if t < 0:
            return
        for tr in self.best:
            for o in tr:
                if o[0] == t and tr in self.ids:
                    self.committed.setdefault(self.ids[tr], {})[t] = o[1]

    def current_tracks(
        self, max_age: int | None = None
    ) -> dict[int, tuple[NDArray[np.float64], NDArray[np.float64]]]:
        """The tracks of the current MAP hypothesis, now: id -> ``(x, P)``, the constant-velocity
        state ``[x, y, vx, vy]`` and covariance filtered through the track's observations in the
        window and predicted to the latest step. Tracks whose last observation is more than
        ``max_age`` steps old (default ``max_gap``) are left out. Call after :meth:`step`."""
        c = self.config
        now = len(self.observations) - 1
        age_limit = c.max_gap if max_age is None else max_age
        f1, q1 = _cv_matrices(c.dt, c.accel_std)
        out = {}
        for tr in self.best:
            ident = self.ids.get(tr)
            if ident is None or now - tr[-1][0] > age_limit:
                continue
            _, states = self._kalman_full(tr)
            t, x, p = states[-1]
            for _ in range(now - t):
                x, p = f1 @ x, f1 @ p @ f1.T + q1
            out[ident] = (x, 0.5 * (p + p.T))
        return dict(sorted(out.items()))

    def forget_past(self) -> None:
        """Free what has left the window, for a tracker that runs indefinitely and reads
        :meth:`current_tracks`: the observations before the window (their steps stay, empty)
        and the committed associations (:meth:`tracks` then covers only later commits). The
        current tracks are unchanged: the sampler only looks inside the window."""
        t_lo = max(0, len(self.observations) - self.config.window)
        empty = np.empty((0, 2))
        for t in range(self._forgotten, t_lo):
            self.observations[t] = empty
        self._forgotten = max(self._forgotten, t_lo)
        self.committed.clear()

    def finish(self) -> None:
        """Commit every observation still in the window (end of the data)."""
        for tr in self.best:
            for o in tr:
                if tr in self.ids:
                    self.committed.setdefault(self.ids[tr], {})[o[0]] = o[1]
        self.best = []

    def tracks(self) -> dict[int, tuple[NDArray[np.int64], NDArray[np.float64]]]:
        """Committed tracks: id → (time steps, Kalman-filtered positions (n, 2)) from the first to
        the last observation, predictions at missed steps. Call :meth:`finish` first at the end."""
        out = {}
        for ident, assoc in sorted(self.committed.items()):
            if len(assoc) < 2:
                continue
            key = tuple(sorted(assoc.items()))
            _, states = self._kalman(key)
            f1, _ = _cv_matrices(self.config.dt, self.config.accel_std)
            times, pos = [], []
            for (t0, x0), (t1, _) in zip(states, [*states[1:], (states[-1][0] + 1, None)]):
                x = x0
                for t in range(t0, t1):
                    times.append(t)
                    pos.append(x[:2].copy())
                    x = f1 @ x
            out[ident] = (np.array(times), np.array(pos))
        return out
