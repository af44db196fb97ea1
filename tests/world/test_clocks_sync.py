"""Clock translation: RBS regression and hop-by-hop elapsed-time translation stay within bounds."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.world.clocks import HopTranslation, NodeClock, RbsDomain, fit_clock_map


def test_clock_model_and_inverse():
    c = NodeClock(offset=0.3, skew=40e-6)
    assert c.local(100.0) == pytest.approx(100.004 + 0.3)
    assert c.true_time(c.local(12.5)) == pytest.approx(12.5)
    jumped = NodeClock(0.0, 0.0, jumps=((5.0, 2.0),))
    assert jumped.local([4.0, 6.0]) == pytest.approx([4.0, 8.0])
    with pytest.raises(ConfigError):
        jumped.true_time(1.0)


def test_fit_clock_map_exact_line():
    x = np.array([1.0, 2.0, 3.0])
    assert fit_clock_map(x, 0.5 + 1.0001 * x) == pytest.approx((0.5, 1.0001))
    with pytest.raises(ConfigError):
        fit_clock_map([1.0], [2.0])


def test_rbs_translation_error_below_100_us():
    rng = np.random.default_rng(0)
    clocks = {k: NodeClock.random(rng) for k in ("fusion", "cam1", "cam2", "gateway")}
    rbs = RbsDomain(clocks, "fusion", rng)
    rbs.broadcast_until(60.0)
    errors = []
    for t in rng.uniform(5.0, 60.0, 200):
        node = ("cam1", "cam2", "gateway")[int(rng.integers(3))]
        ref = rbs.to_reference(node, float(clocks[node].local(t)))
        errors.append(ref - float(clocks["fusion"].local(t)))
    assert np.max(np.abs(errors)) < 100e-6


def test_hop_translation_error_bound():
    rng = np.random.default_rng(1)
    hop = HopTranslation(jitter=5e-6)
    worst = 0.0
    for _ in range(200):
        route = [NodeClock.random(rng) for _ in range(4)]
        stays = list(rng.uniform(0.005, 0.05, 3))
        local, arrive = hop.translate(10.0, route, stays, [0.005] * 3, rng)
        worst = max(worst, abs(local - float(route[-1].local(10.0))))
        assert arrive == pytest.approx(10.0 + sum(stays) + 0.015)
    # skew error ≤ 50 ppm × 150 ms residence plus four 5 µs jitters (≈ 5 σ)
    assert worst < 50e-6 * 0.15 + 5 * 5e-6 * 2
    with pytest.raises(ConfigError):
        hop.translate(0.0, [NodeClock()], [0.1], [0.1], rng)
