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
of independent per-track scores (:meth:`HypothesisSampler.track_score`), which are memoised.

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
window are committed to their track, and track identities persist through the overlap. The
tracker is pure: everything carried between steps is an :class:`AssociationState` value
(``state = tracker.step(state, observations, rng)``).

Observation noise: ``config.obs_std`` (isotropic, Oh et al.'s ``R = σ² I``) unless a step's
observations come with their own ``(n, 2, 2)`` covariances (``step(..., covariances=)``), e.g.
triangulated points with elongated error ellipses; then each observation's covariance is its
``R`` in the track score, its position block of a new track's prior, and its gate radius
(``2 sqrt(λ_max)`` instead of ``2 σ``).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, invalid

Obs = tuple[int, int]  # (time step, index of the observation at that step)
TrackKey = tuple[Obs, ...]
STOP: Obs = (-1, -1)  # end of a growth path (see HypothesisSampler._grow)


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
class MCMCDAStats:
    """Diagnostic counters of the Metropolis-Hastings chain (not part of any result)."""

    accepted: int = 0
    proposed: int = 0


@dataclass
class _Memo:
    """Scores and gate tests already computed for one observation history (pure functions of
    it, kept only for speed). ``steps`` is the length of the history it belongs to: a state
    that is not at the end of this history (an older state stepped again) starts a fresh memo."""

    steps: int = 0
    scores: dict[TrackKey, float] = field(default_factory=dict)
    gates: dict[tuple[Obs, Obs], bool] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class AssociationState:
    """Everything online MCMCDA carries from one step to the next.

    ``observations[k]`` holds the ``(n, 2)`` observations of step ``offset + k`` (steps before
    ``offset`` were forgotten, :meth:`MCMCDA.forget_past`); ``covariances[k]`` their
    ``(n, 2, 2)`` covariances, or None (``obs_std``); ``best`` the MAP hypothesis of the
    window (tracks as tuples of ``(step, index)``); ``ids`` its track identities; ``committed``
    id -> {step: observation index} for observations that have left the window.
    """

    observations: tuple[NDArray[np.float64], ...] = ()
    covariances: tuple[NDArray[np.float64] | None, ...] = ()
    offset: int = 0
    best: tuple[TrackKey, ...] = ()
    ids: Mapping[TrackKey, int] = field(default_factory=dict)
    committed: Mapping[int, Mapping[int, int]] = field(default_factory=dict)
    next_id: int = 0
    memo: _Memo = field(default_factory=_Memo, repr=False)

    @property
    def steps(self) -> int:
        """Number of steps seen so far (the next step's index)."""
        return self.offset + len(self.observations)

    def observation(self, o: Obs) -> NDArray[np.float64]:
        return self.observations[o[0] - self.offset][o[1]]


class HypothesisSampler:
    """The Metropolis-Hastings chain over association hypotheses of a fixed set of observations
    (Oh et al. 2009, Alg. 1; module docstring): the posterior score of a track, the eight moves
    and the accept/reject step. ``observations[t]`` are the ``(n, 2)`` observations of step
    ``offset + t``."""

    def __init__(
        self,
        config: MCMCDAConfig,
        observations: Sequence[NDArray[np.float64]],
        rng: np.random.Generator,
        *,
        offset: int = 0,
        stats: MCMCDAStats | None = None,
        memo: _Memo | None = None,
        covariances: Sequence[NDArray[np.float64] | None] | None = None,
    ) -> None:
        self.config = config
        self.observations = [np.asarray(o, float).reshape(-1, 2) for o in observations]
        iso = config.obs_std**2 * np.eye(2)
        covs = [None] * len(self.observations) if covariances is None else list(covariances)
        self._covs = [
            np.broadcast_to(iso, (len(o), 2, 2)) if c is None else np.asarray(c, float)
            for o, c in zip(self.observations, covs)
        ]
        self._sds = [_largest_sd(c) for c in self._covs]
        self.offset = offset
        self.rng = rng
        self.stats = MCMCDAStats() if stats is None else stats
        memo = _Memo() if memo is None else memo
        self._cache = memo.scores
        self._gate_cache = memo.gates

    def _obs(self, o: Obs) -> NDArray[np.float64]:
        return self.observations[o[0] - self.offset][o[1]]

    def _cov(self, o: Obs) -> NDArray[np.float64]:
        return self._covs[o[0] - self.offset][o[1]]

    def _sd(self, o: Obs) -> float:
        return float(self._sds[o[0] - self.offset][o[1]])

    # ---- model -------------------------------------------------------------------------
    def gate(self, a: Obs, b: Obs) -> bool:
        """Can observation ``b`` follow ``a`` on one track (within ``max_gap`` steps and reach)."""
        gap = b[0] - a[0]
        if gap < 1 or gap > self.config.max_gap:
            return False
        d = self._obs(b) - self._obs(a)
        reach = self.config.max_speed * gap * self.config.dt + 2 * max(self._sd(a), self._sd(b))
        return bool(d @ d <= reach * reach)

    def kalman(self, track: TrackKey) -> tuple[float, list[tuple[int, NDArray[np.float64]]]]:
        """Innovation log-likelihood of a track and its filtered states at its observations."""
        ll, states = self.kalman_full(track)
        return ll, [(t, x) for t, x, _ in states]

    def kalman_full(
        self, track: TrackKey
    ) -> tuple[float, list[tuple[int, NDArray[np.float64], NDArray[np.float64]]]]:
        """:meth:`kalman` with the filtered covariances too: ``(ll, [(t, x, P), ...])``."""
        c = self.config
        f1, q1 = _cv_matrices(c.dt, c.accel_std)
        y0 = self._obs(track[0])
        x = np.array([y0[0], y0[1], 0.0, 0.0])
        p = np.diag([0.0, 0.0, c.init_speed_std**2, c.init_speed_std**2])
        p[:2, :2] = self._cov(track[0])
        ll = 0.0
        states = [(track[0][0], x.copy(), p.copy())]
        for prev, cur in itertools.pairwise(track):
            for _ in range(cur[0] - prev[0]):
                x = f1 @ x
                p = f1 @ p @ f1.T + q1
            y = self._obs(cur)
            s = p[:2, :2] + self._cov(cur)
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
        score += self.kalman(track)[0]
        self._cache[key] = float(score)
        return float(score)

    # ---- moves -------------------------------------------------------------------------
    def _free(self, used: set[Obs], t: int) -> list[Obs]:
        k = t - self.offset
        if k < 0 or k >= len(self.observations):
            return []
        return [(t, j) for j in range(len(self.observations[k])) if (t, j) not in used]

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
            hit = self._gate_cache[key] = self.gate(*key)
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

    def propose(
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

    def total(self, tracks: Sequence[TrackKey], t_end: int) -> float:
        return sum(self.track_score(t, t_end) for t in tracks)

    def mh_step(
        self, tracks: list[TrackKey], score: float, t_lo: int, t_hi: int
    ) -> tuple[list[TrackKey], float]:
        """One Metropolis-Hastings transition on the hypotheses of steps ``t_lo..t_hi`` (inclusive).

        Accepts with ``min(1, P(ω'|Y) q(ω|ω') / (P(ω|Y) q(ω'|ω)))`` (Oh et al. 2009, Alg. 1),
        so the chain's stationary law is ``P(ω | Y)``; ``score`` is ``log P(ω | Y)`` up to a constant.
        """
        self.stats.proposed += 1
        move = self.propose(tracks, t_lo, t_hi)
        if move is None:
            return tracks, score
        proposal, log_ratio = move
        new = self.total(proposal, t_hi)
        if np.log(self.rng.random() + 1e-300) < new - score + log_ratio:
            self.stats.accepted += 1
            return proposal, new
        return tracks, score


@dataclass
class MCMCDA:
    """Online MCMCDA, pure: ``state = tracker.step(state, observations, rng)`` per step, from
    ``tracker.initial_state()``; read :meth:`current_tracks` (the estimates now, after each step)
    or, at the end, :meth:`tracks` of ``tracker.finish(state)`` (the committed tracks). The
    tracker holds its configuration and diagnostic counters (``stats``) only."""

    config: MCMCDAConfig = field(default_factory=MCMCDAConfig)
    stats: MCMCDAStats = field(default_factory=MCMCDAStats)

    def initial_state(self) -> AssociationState:
        return AssociationState()

    def sampler(
        self, state: AssociationState, rng: np.random.Generator | None = None
    ) -> HypothesisSampler:
        """The chain over ``state``'s observations (sharing its memo and this tracker's stats)."""
        return HypothesisSampler(
            self.config,
            state.observations,
            np.random.default_rng(0) if rng is None else rng,
            offset=state.offset,
            stats=self.stats,
            memo=state.memo,
            covariances=_padded(state.covariances, len(state.observations)),
        )

    # ---- online loop -------------------------------------------------------------------
    def step(
        self,
        state: AssociationState,
        observations: ArrayLike,
        rng: np.random.Generator,
        covariances: ArrayLike | None = None,
    ) -> AssociationState:
        """Add one step's observations ``(n, 2)`` (with their ``(n, 2, 2)`` covariances, or
        None for ``config.obs_std``); the new state holds the window's MAP hypothesis. Rows
        with a non-finite position or covariance are dropped."""
        y = np.asarray(observations, float).reshape(-1, 2)
        cov = _checked_covariances(covariances, len(y))
        keep = np.all(np.isfinite(y), axis=1)
        if cov is not None:
            keep &= np.all(np.isfinite(cov), axis=(1, 2))
            cov = cov[keep]
        y = y[keep]
        memo = state.memo if state.memo.steps == state.steps else _Memo()
        memo.steps = state.steps + 1
        new_obs = (*state.observations, y)
        new_covs = (*_padded(state.covariances, len(state.observations)), cov)
        chain = HypothesisSampler(
            self.config,
            new_obs,
            rng,
            offset=state.offset,
            stats=self.stats,
            memo=memo,
            covariances=new_covs,
        )
        t_hi = state.steps
        t_lo = max(0, t_hi - self.config.window + 1)
        # Observations at t_lo - 1 just left the window: commit them.
        committed = _commit(state.committed, state.best, state.ids, lambda t: t == t_lo - 1)
        ids = dict(state.ids)
        current = []
        for tr in state.best:
            kept = tuple(o for o in tr if o[0] >= t_lo)
            if len(kept) >= 2:
                current.append(kept)
                if tr in ids:
                    ids.setdefault(kept, ids[tr])
        current_score = chain.total(current, t_hi)
        best, best_score = list(current), current_score
        for _ in range(self.config.n_mc):
            current, current_score = chain.mh_step(current, current_score, t_lo, t_hi)
            if current_score > best_score:
                best, best_score = list(current), current_score
        ids, next_id = _assign_ids(state.best, ids, best, state.next_id)
        if len(memo.scores) > 200_000:
            memo.scores.clear()
            memo.gates.clear()
        return replace(
            state,
            observations=new_obs,
            covariances=new_covs,
            best=tuple(best),
            ids=ids,
            committed=committed,
            next_id=next_id,
            memo=memo,
        )

    def current_tracks(
        self, state: AssociationState, max_age: int | None = None
    ) -> dict[int, tuple[NDArray[np.float64], NDArray[np.float64]]]:
        """The tracks of the current MAP hypothesis, now: id -> ``(x, P)``, the constant-velocity
        state ``[x, y, vx, vy]`` and covariance filtered through the track's observations in the
        window and predicted to the latest step. Tracks whose last observation is more than
        ``max_age`` steps old (default ``max_gap``) are left out."""
        c = self.config
        now = state.steps - 1
        age_limit = c.max_gap if max_age is None else max_age
        f1, q1 = _cv_matrices(c.dt, c.accel_std)
        chain = self.sampler(state)
        out = {}
        for tr in state.best:
            ident = state.ids.get(tr)
            if ident is None or now - tr[-1][0] > age_limit:
                continue
            _, states = chain.kalman_full(tr)
            t, x, p = states[-1]
            for _ in range(now - t):
                x, p = f1 @ x, f1 @ p @ f1.T + q1
            out[ident] = (x, 0.5 * (p + p.T))
        return dict(sorted(out.items()))

    def forget_past(self, state: AssociationState) -> AssociationState:
        """Drop what has left the window, for a tracker that runs indefinitely and reads
        :meth:`current_tracks`: the observations before the window and the committed
        associations (:meth:`tracks` then covers only later commits). The current tracks are
        unchanged: the sampler only looks inside the window."""
        t_lo = max(0, state.steps - self.config.window)
        drop = max(0, t_lo - state.offset)
        return replace(
            state,
            observations=state.observations[drop:],
            covariances=_padded(state.covariances, len(state.observations))[drop:],
            offset=state.offset + drop,
            committed={},
        )

    def finish(self, state: AssociationState) -> AssociationState:
        """Commit every observation still in the window (end of the data)."""
        committed = _commit(state.committed, state.best, state.ids, lambda t: True)
        return replace(state, best=(), committed=committed)

    def tracks(
        self, state: AssociationState
    ) -> dict[int, tuple[NDArray[np.int64], NDArray[np.float64]]]:
        """Committed tracks: id → (time steps, Kalman-filtered positions (n, 2)) from the first to
        the last observation, predictions at missed steps. :meth:`finish` the state first."""
        chain = self.sampler(state)
        f1, _ = _cv_matrices(self.config.dt, self.config.accel_std)
        out = {}
        for ident, assoc in sorted(state.committed.items()):
            if len(assoc) < 2:
                continue
            key = tuple(sorted(assoc.items()))
            _, states = chain.kalman(key)
            times, pos = [], []
            for (t0, x0), (t1, _) in zip(states, [*states[1:], (states[-1][0] + 1, None)]):
                x = x0
                for t in range(t0, t1):
                    times.append(t)
                    pos.append(x[:2].copy())
                    x = f1 @ x
            out[ident] = (np.array(times), np.array(pos))
        return out


def _largest_sd(cov: NDArray[np.float64]) -> NDArray[np.float64]:
    """``sqrt`` of the largest eigenvalue of each ``(2, 2)`` covariance (closed form)."""
    half_tr = 0.5 * (cov[:, 0, 0] + cov[:, 1, 1])
    det = cov[:, 0, 0] * cov[:, 1, 1] - cov[:, 0, 1] * cov[:, 1, 0]
    return np.asarray(np.sqrt(half_tr + np.sqrt(np.maximum(half_tr**2 - det, 0.0))), float)


def _checked_covariances(covariances: ArrayLike | None, n: int) -> NDArray[np.float64] | None:
    """A step's ``(n, 2, 2)`` covariances (None: ``obs_std``); a clear error for a bad shape."""
    if covariances is None:
        return None
    cov = np.asarray(covariances, float)
    if cov.shape != (n, 2, 2):
        raise ConfigError(
            invalid("covariances.shape", cov.shape, f"({n}, 2, 2): one per observation")
        )
    return cov


def _padded(
    covariances: tuple[NDArray[np.float64] | None, ...], n: int
) -> tuple[NDArray[np.float64] | None, ...]:
    """``covariances`` padded with None to ``n`` steps (states built before covariances)."""
    return covariances + (None,) * (n - len(covariances))


def _commit(
    committed: Mapping[int, Mapping[int, int]],
    best: Sequence[TrackKey],
    ids: Mapping[TrackKey, int],
    when: Callable[[int], bool],
) -> dict[int, dict[int, int]]:
    """``committed`` plus the observations of ``best``'s identified tracks at steps ``when``."""
    out = {k: dict(v) for k, v in committed.items()}
    for tr in best:
        for o in tr:
            if when(o[0]) and tr in ids:
                out.setdefault(ids[tr], {})[o[0]] = o[1]
    return out


def _assign_ids(
    previous: Sequence[TrackKey], ids: dict[TrackKey, int], new: list[TrackKey], next_id: int
) -> tuple[dict[TrackKey, int], int]:
    """Identities for the tracks of the new MAP hypothesis: each takes the identity of the old
    track it shares most observations with (longest first), else a fresh one."""
    old = [(set(t), ids[t]) for t in previous if t in ids]
    old += [
        (set(t), i)
        for t, i in ids.items()
        if t not in previous and any(set(t) & set(n) for n in new)
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
            ident = next_id
            next_id += 1
        taken.add(ident)
        ids[tr] = ident
    return {t: i for t, i in ids.items() if t in new}, next_id
