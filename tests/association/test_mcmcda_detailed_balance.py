"""MCMCDA's Metropolis-Hastings chain samples P(ω | Y): visit frequencies against the enumerated posterior.

A tiny window (4 steps, 6 observations) has 94 hypotheses (27 possible tracks). We enumerate
them, score each with the tracker's own posterior (Oh et al. 2009, Eq. 8) and compare the
chain's visit frequencies with the normalised posterior. Without the proposal ratios (the old
MAP search) the same chain is far off, so the check has the power to see a wrong ratio.
"""

import numpy as np

from fusetrack.association.mcmcda import HypothesisSampler, MCMCDAConfig

CFG = MCMCDAConfig(
    dt=1.0, max_speed=2.0, max_gap=2, obs_std=1.0, accel_std=1.0, p_detect=0.7, p_terminate=0.2,
    birth_rate=0.5, false_alarm_rate=0.5, area=20.0, init_speed_std=2.0, stop_prob=0.4,
)  # fmt: skip
OBS = [[[0.0, 0.0], [1.0, 2.0]], [[1.0, 0.5]], [[2.0, 0.8], [2.5, 2.0]], [[3.0, 1.2]]]


def _tracker(seed):
    return HypothesisSampler(CFG, [np.array(o) for o in OBS], np.random.default_rng(seed))


def _posterior(m):
    """Every hypothesis (set of disjoint gated tracks of >= 2 observations) and its probability."""
    allobs = [(t, j) for t, o in enumerate(OBS) for j in range(len(o))]

    def grow(prefix):
        out = [tuple(prefix)] if len(prefix) >= 2 else []
        for o in allobs:
            if o[0] > prefix[-1][0] and m.gate(prefix[-1], o):
                out += grow([*prefix, o])
        return out

    tracks = [t for o in allobs for t in grow([o])]

    def hyps(free, start):
        yield ()
        for i in range(start, len(tracks)):
            if set(tracks[i]) <= free:
                for rest in hyps(free - set(tracks[i]), i + 1):
                    yield (tracks[i], *rest)

    hs = [frozenset(h) for h in hyps(set(allobs), 0)]
    logp = np.array([m.total(list(h), len(OBS) - 1) for h in hs])
    p = np.exp(logp - logp.max())
    return len(tracks), hs, p / p.sum()


def _frequencies(m, hs, n):
    index = {h: i for i, h in enumerate(hs)}
    counts = np.zeros(len(hs))
    cur, score = [], m.total([], len(OBS) - 1)
    for _ in range(n):
        cur, score = m.mh_step(cur, score, 0, len(OBS) - 1)
        counts[index[frozenset(cur)]] += 1  # KeyError here = the chain left the valid hypotheses
    return counts / n


def test_chain_visits_hypotheses_in_proportion_to_the_posterior():
    m = _tracker(3)
    n_tracks, hs, p = _posterior(m)
    assert (n_tracks, len(hs)) == (27, 94)
    f = _frequencies(m, hs, 100_000)
    tv = 0.5 * np.abs(f - p).sum()
    assert tv < 0.05, tv  # measured 0.017-0.031 over seeds; Monte Carlo error ~ 1/sqrt(n_eff)
    top = np.argsort(p)[-6:]  # the six most probable hypotheses, each within a few MC sd
    assert np.all(np.abs(f[top] - p[top]) < 0.03 + 0.1 * p[top]), (f[top], p[top])
    assert 0.05 < m.stats.accepted / m.stats.proposed < 0.9


def test_without_proposal_ratios_the_chain_is_wrong():
    m = _tracker(4)
    _, hs, p = _posterior(m)
    propose = m.propose

    def no_ratio(*args):
        out = propose(*args)
        return None if out is None else (out[0], 0.0)

    m.propose = no_ratio  # type: ignore[method-assign]
    f = _frequencies(m, hs, 30_000)
    assert 0.5 * np.abs(f - p).sum() > 0.3  # measured 0.57
