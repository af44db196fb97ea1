"""Lee 2009 Ch. 3: each trigger on constructed configurations (Figs. 3-8, 3-10, 3-11, 3-13; C10)."""

import math

import numpy as np
import pytest

from fusetrack.core import Filter, Measurement
from fusetrack.core.errors import ConfigError, MeasurementError
from fusetrack.filters.multi_model_pf import (
    MultiModelBearingPF,
    MultiModelBelief,
    reset_to_fix,
    turn_models,
)
from fusetrack.management.camera_triggering import (
    AcousticTracker,
    CooperationPolicy,
    bearing_gate_trigger,
    count_trigger,
    ellipse_trigger,
    run_cooperation,
)
from fusetrack.sensors.unlabelled_bearings import merge_close, simulate_bearings

D = math.pi / 180
S = (0.0, 0.0)


def test_count_trigger_catches_merge_entry_exit_silence():
    assert count_trigger(1, 2)  # two objects merged into one bearing / one silent / one left
    assert count_trigger(3, 2)  # a new object
    assert not count_trigger(2, 2)


def test_gate_catches_what_count_misses():
    """Fig. 3-8(b)-(f): one object leaves and another appears at once -- the count stays equal,
    but the tracked object's estimate has no bearing within 2 sigma."""
    sigma = math.sqrt(3) * D
    est = np.array([10.0, 10.0])  # bearing 45 deg
    z = np.array([80 * D, 10 * D])  # bearings of the two objects now present
    assert not count_trigger(len(z), 2)
    assert bearing_gate_trigger(est, S, z, sigma)
    assert not bearing_gate_trigger(est, S, np.array([46 * D, 10 * D]), sigma)
    assert bearing_gate_trigger(est, S, np.array([]), sigma)  # no bearing at all


def test_ellipse_catches_what_gate_misses():
    """Fig. 3-11/3-13: the estimate sits on a bearing (the gate passes) but away from every
    model's particle cloud (a deviated estimate averaged between two clouds)."""
    rng = np.random.default_rng(0)
    cloud_a = np.array([10.0, 10.0]) + 0.1 * rng.standard_normal((500, 2))
    cloud_b = np.array([20.0, 20.0]) + 0.1 * rng.standard_normal((500, 2))
    est = np.array([15.0, 15.0])  # on the 45 deg bearing, between the clouds
    assert not bearing_gate_trigger(est, S, np.array([45 * D]), math.sqrt(3) * D)
    assert ellipse_trigger(est, np.stack([cloud_a, cloud_b]))
    assert not ellipse_trigger(np.array([10.05, 10.0]), np.stack([cloud_a, cloud_b]))


def test_merge_and_unlabelled_bearings():
    m = merge_close(np.array([10 * D, 11 * D, 50 * D]), 2 * D)
    assert sorted(m) == pytest.approx([10.5 * D, 50 * D])
    rng = np.random.default_rng(0)
    z = simulate_bearings(np.array([[1, 0.0], [0, 1.0]]), np.array([True, False]), S, 0.0, rng)
    assert z == pytest.approx([0.0])


def test_filter_bad_input_and_no_bearing():
    f = MultiModelBearingPF(turn_models(1.0, 0.01), S, 0.03, 50)
    rng = np.random.default_rng(0)
    p = f.initial_belief(np.array([10, 10, 0.1, 0]), np.array([0.1, 0.1, 0.01, 0.01]), rng)
    p2 = f.step(p, 1.0, [], rng)  # silence: prediction only
    assert np.all(np.isfinite(p2.mean)) and p2.states.shape == p.states.shape
    far = f.step(p, 1.0, [Measurement(1.0, "mic", math.pi)], rng)  # weights tiny, not NaN
    assert np.all(np.isfinite(far.mean))
    with pytest.raises(MeasurementError):
        f.step(p, 1.0, [Measurement(1.0, "mic", np.nan)], rng)
    with pytest.raises(ConfigError):
        MultiModelBearingPF(turn_models(1.0, 0.01), S, 0.0)
    with pytest.raises(ConfigError):
        CooperationPolicy(period=0)


def test_triggered_cooperation_beats_none_and_camera_silence_is_survived():
    T = 60
    truth = np.zeros((T, 2, 4))
    truth[0] = [[20, 5, -0.2, 0.2], [5, 20, 0.2, -0.1]]
    for k in range(1, T):
        truth[k] = truth[k - 1]
        truth[k, :, :2] += truth[k - 1, :, 2:]
    present = np.ones((T, 2), bool)
    present[40:, 1] = False  # object 2 leaves
    kw = {"tracker": AcousticTracker(turn_models(1.0, 0.01), dt=1.0, n_particles=100)}
    none = run_cooperation(
        truth,
        present,
        present,
        S,
        math.sqrt(3) * D,
        CooperationPolicy(),
        np.random.default_rng(1),
        **kw,
    )
    trig = run_cooperation(
        truth,
        present,
        present,
        S,
        math.sqrt(3) * D,
        CooperationPolicy.triggering(),
        np.random.default_rng(1),
        **kw,
    )
    err = lambda r: np.nanmean(np.sum((r.estimates[..., :2] - truth[..., :2]) ** 2, -1))  # noqa: E731
    assert err(trig) < err(none)
    assert (
        not trig.tracked[45, 1] and trig.fired[40, 0]
    )  # the departure fired (3.14), track dropped
    dead = run_cooperation(
        truth,
        present,
        present,
        S,
        math.sqrt(3) * D,
        CooperationPolicy.triggering(),
        np.random.default_rng(1),
        camera_available=np.zeros(T, bool),
        **kw,
    )
    assert not dead.camera_updates.any() and np.isfinite(dead.estimates[dead.tracked]).all()


def test_fast_bank_propagation_equals_each_models_map():
    models = turn_models(0.7, 0.0)
    f = MultiModelBearingPF(models, S, 0.03, 64)
    p = np.random.default_rng(0).standard_normal((64, 4))
    p[0, 2:] = 0.0  # a particle at rest: every model is constant velocity there
    fast = f.propagate_every_model(p, 0.5, np.random.default_rng(1))
    slow = np.stack([m.mean(p, 0.5) for m in models])
    assert np.allclose(fast, slow, atol=1e-12)


def test_literal_jpda_chain_shrinks_towards_origin():
    """Spec note on Eqs. 3.7-3.11: with jointly normalised weights the printed chain is not convex."""
    rng = np.random.default_rng(5)
    p = np.array([20.0, 20.0, 0.1, 0.0]) + np.array([0.2, 0.2, 0.01, 0.01]) * rng.standard_normal(
        (200, 4)
    )
    z = np.array([45 * D, 44 * D, 80 * D])
    out = {}
    for est in ("consistent", "literal"):
        f = MultiModelBearingPF(turn_models(1.0, 0.0), S, 2 * D, 200, estimator=est)
        bearings = [Measurement(1.0, "mic", z_i) for z_i in z]
        out[est] = f.step(MultiModelBelief.uniform(p), 1.0, bearings, np.random.default_rng(1)).mean
    assert np.linalg.norm(out["consistent"][:2]) == pytest.approx(
        np.linalg.norm(p[:, :2].mean(0)), rel=0.05
    )
    assert np.linalg.norm(out["literal"][:2]) < 0.9 * np.linalg.norm(out["consistent"][:2])


def test_step_is_predict_then_update_with_the_same_draws():
    """The fused Numba step equals ``update(predict(...))`` draw for draw; the model index of
    every resampled particle is the model that moved its ancestor; a camera fix is a new belief."""
    f = MultiModelBearingPF(turn_models(1.0, 0.01), S, 2 * D, 80)
    assert isinstance(f, Filter)
    b0 = f.initial_belief(
        np.array([20, 20, 0.1, 0]), np.array([0.2, 0.2, 0.02, 0.02]), np.random.default_rng(3)
    )
    zs = [Measurement(1.0, "mic", 45.2 * D), Measurement(1.0, "mic", 10 * D)]
    fused = f.step(b0, 1.0, zs, np.random.default_rng(4))
    rng = np.random.default_rng(4)
    pred = f.predict(b0, 1.0, rng)
    assert pred.states.shape == (240, 4) and np.array_equal(pred.model, np.repeat([0, 1, 2], 80))
    ref = f.update(pred, zs, rng)
    np.testing.assert_allclose(fused.states, ref.states, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fused.mean, ref.mean, rtol=0, atol=1e-12)
    assert np.array_equal(fused.model, ref.model) and fused.predictions.shape == (3, 80, 4)
    idx = [np.flatnonzero(np.all(pred.states == s, axis=1))[0] for s in ref.states[:5]]
    assert np.array_equal(pred.model[idx], ref.model[:5])
    fixed = reset_to_fix(ref, np.array([1.0, 2.0]), 0.1, np.random.default_rng(0))
    assert np.array_equal(fixed.states[:, 2:], ref.states[:, 2:]) and ref is not fixed
    assert np.allclose(fixed.states[:, :2].mean(0), [1.0, 2.0], atol=0.05)
    assert np.array_equal(fixed.mean[:2], [1.0, 2.0])


def test_merge_close_groups_across_the_wrap_and_matches_the_roll_reference():
    # 359.5 and 0.5 deg merge across 0; 90 and 91 merge; 200 stays alone
    b = np.array([0.5, 90.0, 359.5, 200.0, 91.0]) * D
    m = merge_close(b, 2 * D)
    want = [90.5 * D, -160 * D, 0.0]  # after the first real gap (91 -> 200); atan2 range
    np.testing.assert_allclose(m, want, atol=1e-12)
    # the same groups as the np.roll formulation it replaces, to the bit
    s = np.sort(np.mod(b, 2 * math.pi))
    gaps = np.diff(np.append(s, s[0] + 2 * math.pi))
    start = int(np.argmax(gaps >= 2 * D)) + 1
    order, g = np.roll(s, -start), np.roll(gaps, -start)
    groups, cur = [], [order[0]]
    for k in range(1, len(order)):
        if g[k - 1] < 2 * D:
            cur.append(order[k])
        else:
            groups.append(cur)
            cur = [order[k]]
    groups.append(cur)
    ref = np.array([math.atan2(np.sin(gr).sum(), np.cos(gr).sum()) for gr in groups])
    assert np.array_equal(m, ref)
