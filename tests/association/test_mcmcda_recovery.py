"""Online MCMCDA recovers known tracks from clean synthetic detections; peak extraction."""

import numpy as np
import pytest

from fusetrack.association.mcmcda import MCMCDA, HypothesisSampler, MCMCDAConfig
from fusetrack.association.peaks import likelihood_peaks
from fusetrack.core.errors import ConfigError


def test_two_crossing_targets_with_clutter_are_recovered():
    rng = np.random.default_rng(0)
    starts = [np.array([2.0, 8.0]), np.array([33.0, 12.0])]
    vels = [np.array([10.0, 0.5]), np.array([-10.0, -0.5])]
    tracker = MCMCDA(MCMCDAConfig(n_mc=300))
    state, draws = tracker.initial_state(), np.random.default_rng(1)
    steps = 14
    for t in range(steps):
        obs = [
            p + v * 0.25 * t + rng.normal(0, 0.3, 2)
            for p, v in zip(starts, vels)
            if rng.random() < 0.95
        ]
        if t % 4 == 1:
            obs.append(rng.uniform([0, 0], [35, 20]))
        state = tracker.step(state, np.array(obs).reshape(-1, 2), draws)
    tracks = tracker.tracks(tracker.finish(state))
    long_tracks = {k: v for k, v in tracks.items() if len(v[0]) >= steps - 2}
    assert len(long_tracks) == 2
    for times, pos in long_tracks.values():
        truths = [s + v * 0.25 * times[:, None] for s, v in zip(starts, vels)]
        err = min(np.linalg.norm(pos - tr, axis=1).mean() for tr in truths)
        assert err < 0.6
    assert tracker.stats.accepted > 0


def test_scores_prefer_the_true_association():
    obs = [np.array([[1.0 + 2.5 * t, 5.0], [30.0 - 2.5 * t, 15.0]]) for t in range(4)]
    tracker = HypothesisSampler(MCMCDAConfig(), obs, np.random.default_rng(0))
    good = tuple((t, 0) for t in range(4))
    bad = ((0, 0), (1, 1), (2, 0), (3, 1))
    assert tracker.track_score(good, 3) > 0 > tracker.track_score(bad, 3)


def test_config_validation():
    with pytest.raises(ConfigError, match="p_detect"):
        MCMCDAConfig(p_detect=1.5)


def test_likelihood_peaks_centroids():
    x = np.arange(40) * 0.5 + 0.25
    y = np.arange(20) * 0.5 + 0.25
    xx, yy = np.meshgrid(x, y, indexing="ij")
    lk = np.exp(-((xx - 5.0) ** 2 + (yy - 4.0) ** 2) / 0.5) + 0.6 * np.exp(
        -((xx - 15.0) ** 2 + (yy - 6.0) ** 2) / 0.5
    )
    peaks = likelihood_peaks(lk, x, y)
    assert peaks.shape == (2, 2)
    assert peaks[0] == pytest.approx([5.0, 4.0], abs=0.1)
    assert peaks[1] == pytest.approx([15.0, 6.0], abs=0.1)
    assert likelihood_peaks(np.zeros((40, 20)), x, y).shape == (0, 2)


def test_step_is_pure_and_an_older_state_can_be_stepped_again():
    rng = np.random.default_rng(5)
    obs = [np.array([[1.0 + 2.5 * t, 5.0], [30.0 - 2.5 * t, 15.0]]) for t in range(6)]
    obs = [o + rng.normal(0, 0.2, o.shape) for o in obs]
    tracker = MCMCDA(MCMCDAConfig(n_mc=200))
    states = [tracker.initial_state()]
    for y in obs[:4]:
        states.append(tracker.step(states[-1], y, np.random.default_rng(len(states))))
    s4 = states[4]
    frozen = (s4.steps, s4.best, dict(s4.ids), {k: dict(v) for k, v in s4.committed.items()})
    a = tracker.step(s4, obs[4], np.random.default_rng(9))
    assert (s4.steps, s4.best, dict(s4.ids), dict(s4.committed)) == frozen  # untouched
    # the same step from the same state and seed gives the same state, also after the memo
    # moved on (a = s4 + obs[4] advanced it) and from a state that branched off earlier
    b = tracker.step(s4, obs[4], np.random.default_rng(9))
    assert (a.best, a.ids) == (b.best, b.ids)
    fresh = MCMCDA(MCMCDAConfig(n_mc=200))
    c = fresh.initial_state()
    for k, y in enumerate(obs[:4]):
        c = fresh.step(c, y, np.random.default_rng(k + 1))
    c = fresh.step(c, obs[4], np.random.default_rng(9))
    assert (c.best, c.ids) == (a.best, a.ids)
    assert len(a.best) == 2 and set(tracker.current_tracks(a)) == set(a.ids.values())
