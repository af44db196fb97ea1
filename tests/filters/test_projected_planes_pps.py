"""Lee 2009 Ch. 2: PPS plane filters, combining, switching, the direct 3-D filter and the CRLB."""

import math

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError, MeasurementError, ShapeError
from fusetrack.evaluation.projected_planes_crlb import direct3d_crlb, fused_bound, plane_crlb
from fusetrack.filters.projected_planes import (
    Direct3DFilter,
    ProjectedPlanesTracker,
    fuse_planes,
    select_pairs,
    sir_update,
)
from fusetrack.motion.accel_turn import AccelTurn
from fusetrack.sensors.doa_projection import DoaSensor3D

D = math.pi / 180
SIG = math.sqrt(3) * D


def test_table21_truth_check_values():
    m = AccelTurn(3, (0, 0, 0), (1, 2), -0.01)
    tr = m.trajectory(np.array([10, 130, 18, 1, -0.75, 0.75]), 1.0, 165)
    assert tr[50, :3] == pytest.approx([60, 102.55, 62.80], abs=0.01)
    assert tr[100, :3] == pytest.approx([110, 98.44, 115.19], abs=0.01)
    assert tr[164, :3] == pytest.approx([174, 128.07, 175.12], abs=0.01)


def test_act_positive_alpha_turns_anticlockwise_and_keeps_speed():
    m = AccelTurn(2, (0, 0), (0, 1), 0.5)
    x = m.mean(np.array([0.0, 0.0, 1.0, 0.0]), 0.1)
    assert x[3] > 0  # velocity rotated towards +y
    assert np.hypot(x[2], x[3]) == pytest.approx(1.0)
    # restricted plane keeps the turn only with both axes
    m3 = AccelTurn(3, (0, 0.1, 0.5), (1, 2), -0.01)
    assert m3.restrict((1, 2)).turn_axes == (0, 1)
    xy = m3.restrict((0, 1))
    assert xy.turn_axes is None and xy.accel == (0.0, 0.0)
    coupled = m3.restrict((0, 1), state=np.array([0, 0, 0, 1.0, 0.0, 1.0]))
    assert coupled.accel[1] == pytest.approx(0.01)  # dv_y/dt = -omega v_z, omega = -0.01


def test_sir_update_degenerate_weights_never_nan():
    rng = np.random.default_rng(0)
    p = rng.standard_normal((50, 4))
    out, step = sir_update(p, np.full(50, -np.inf), rng)
    assert step.degenerate and np.all(np.isfinite(step.mean))
    assert out is p


def test_fuse_weighted_and_equal():
    est = {(0, "xy"): np.array([1.0, 2.0, 0.1, 0.2]), (0, "yz"): np.array([4.0, 3.0, 0.4, 0.3])}
    logw = {(0, "xy"): math.log(3.0), (0, "yz"): math.log(1.0)}
    pairs = ((0, "xy"), (0, "yz"))
    w = fuse_planes(est, logw, pairs, weighted=True)
    e = fuse_planes(est, logw, pairs, weighted=False)
    assert w[0] == 1.0 and w[2] == 3.0  # x from xy, z from yz
    assert w[1] == pytest.approx((3 * 2.0 + 4.0) / 4)  # Eq. 2.19
    assert e[1] == pytest.approx(3.0) and e[4] == pytest.approx(0.3)  # Eq. 2.21


def test_multi_sensor_literal_selection_scenario4():
    s1 = DoaSensor3D("a", sigma=SIG)
    s2 = DoaSensor3D("b", (10, 10, 10), SIG, polarity=(-1, -1, -1))
    m = AccelTurn(3, (0, 0.1, 0.5))
    tr = m.trajectory(np.array([2, 1, 2, 0.3, 0.3, 0.3]), 0.1, 50)
    pairs = []
    for n in (0, 12, 13, 49):
        z = np.array([np.stack(s.angles(tr[n, :3])) for s in (s1, s2)])
        pairs.append(select_pairs(z, [s1, s2], "literal")[0])
    assert pairs[0] == ((0, "yz"), (0, "xy")) and pairs[1] == pairs[0]
    assert pairs[2] == ((0, "zx"), (1, "yz")) and pairs[3] == pairs[2]
    with pytest.raises(ConfigError, match="selection"):
        select_pairs(z, [s1, s2], "best")


def test_pps_tracks_scenario1_and_switches_in_scenario3():
    s = DoaSensor3D("a", sigma=SIG)
    truth_m = AccelTurn(3, (0, 0.1, 0.5))
    m = AccelTurn(3, (0, 0.1, 0.5), sigma_a=0.1)
    rng = np.random.default_rng(3)
    tr = truth_m.trajectory(np.array([2, 1, 2, 0.3, 0.3, 0.3]), 0.1, 50)
    z = s.simulate(tr[:, :3], rng)[:, None, :]
    res = ProjectedPlanesTracker([s], m, 300).run(z, 0.1, tr[0], rng)
    planes = [p[1][1] for p in res.pairs]
    assert planes[:13].count("yz") >= 10 and planes[-1] == "zx"
    err = np.sqrt(np.mean((res.weighted[:, :3] - tr[:, :3]) ** 2))
    assert err < 0.3
    assert np.all(np.isfinite(res.weighted))


def test_bad_measurements_raise():
    s = DoaSensor3D("a", sigma=SIG)
    m = AccelTurn(3, sigma_a=0.1)
    tr = ProjectedPlanesTracker([s], m, 10)
    with pytest.raises(ShapeError):
        tr.run(np.zeros((5, 2)), 0.1, np.zeros(6), np.random.default_rng(0))
    z = np.full((3, 1, 2), 1.0)
    z[1, 0, 0] = np.nan
    with pytest.raises(MeasurementError):
        tr.run(z, 0.1, np.array([1.0, 1, 1, 0, 0, 0]), np.random.default_rng(0))


def test_crlb_needs_prior_and_bounds_the_3d_filter():
    """Easy case: the direct 3-D filter started from a prior draw sits at (not below) its CRLB."""
    s = DoaSensor3D("a", sigma=SIG)
    truth_m = AccelTurn(3, (0, 0.1, 0.5))
    tr = truth_m.trajectory(np.array([3, 3, 1, 1, 1, 1.0]), 0.1, 30)
    bound = direct3d_crlb(tr, s, truth_m, 0.1, sigma_pos=0.1, sigma_vel=0.1)
    # the bound at step 0 is below the prior (the measurement adds information)
    assert np.all(bound[0, :3] < 0.1)
    # constant velocity and a vanishing prior: scale is unobservable, the bound explodes
    # (with a known nonzero acceleration the scale is observable and it stays finite)
    cv = AccelTurn(3)
    tr_cv = cv.trajectory(np.array([3, 3, 1, 1, 1, 1.0]), 0.1, 30)
    weak = direct3d_crlb(tr_cv, s, cv, 0.1, sigma_pos=1e6, sigma_vel=1e6)
    assert np.max(weak[-1, :3]) > 1e3
    assert np.max(direct3d_crlb(tr, s, truth_m, 0.1, sigma_pos=1e6, sigma_vel=1e6)[-1, :3]) < 1e3
    rng = np.random.default_rng(11)
    sq = []
    m = AccelTurn(3, (0, 0.1, 0.5), sigma_a=1e-3)
    for _ in range(40):
        z = s.simulate(tr[:, :3], rng)[:, None, :]
        x0 = tr[0] + 0.1 * rng.standard_normal(6)
        out = Direct3DFilter(s, m, 400, init_std=(0.1, 0.1)).run(z, 0.1, x0, rng)
        sq.append((out.estimates[:, :3] - tr[:, :3]) ** 2)
    rmse = np.sqrt(np.mean(sq, axis=0)).mean()
    b = bound[:, :3].mean()
    assert 0.8 * b <= rmse <= 1.6 * b


def test_plane_crlb_switched_is_looser_and_fused_combines():
    s = DoaSensor3D("a", sigma=SIG)
    m = AccelTurn(3, (0, 0.1, 0.5))
    tr = m.trajectory(np.array([3, 3, 1, 1, 1, 1.0]), 0.1, 50)
    on = plane_crlb(tr, s, "yz", m, 0.1)
    sel = np.zeros(50, bool)
    sel[:20] = True
    sw = plane_crlb(tr, s, "yz", m, 0.1, selected=sel)
    assert np.allclose(on[:20], sw[:20]) and np.all(sw[20:] >= on[20:] - 1e-12)
    printed = plane_crlb(tr, s, "yz", m, 0.1, transition="printed")
    assert printed.shape == on.shape
    assert fused_bound(np.array([1.0]), np.array([1.0]))[0] == pytest.approx(1 / math.sqrt(2))


def test_trackers_are_pure_filters_and_run_is_their_loop():
    from fusetrack.core.models import Filter

    s = DoaSensor3D("a", sigma=SIG)
    m = AccelTurn(3, (0, 0.1, 0.5), sigma_a=0.1)
    tr = AccelTurn(3, (0, 0.1, 0.5)).trajectory(np.array([2, 1, 2, 0.3, 0.3, 0.3]), 0.1, 8)
    z = s.simulate(tr[:, :3], np.random.default_rng(5))[:, None, :]
    pps = ProjectedPlanesTracker([s], m, 50)
    assert isinstance(pps, Filter) and isinstance(Direct3DFilter(s, m, 50), Filter)
    ref = pps.run(z, 0.1, tr[0], np.random.default_rng(1))
    rng = np.random.default_rng(1)
    b0 = pps.initial_belief(tr[0])
    b1 = pps.update(b0, pps.measurements(0.0, z[0]), rng)
    assert b0.planes == {} and b1.step == 0  # the input belief is untouched
    b2 = pps.update(pps.predict(b1, 0.1, rng), pps.measurements(0.1, z[1]), rng)
    assert b2.fused == pytest.approx(ref.weighted[1], abs=0) and b2.mean is b2.fused
    assert np.all(np.diag(b2.cov) > 0)
    with pytest.raises(ShapeError, match="measurements"):
        pps.update(b2, [], rng)


def test_projected_plane_likelihood_peaks_at_the_true_plane_bearing():
    from fusetrack.sensors.doa_plane_likelihood import DoaCone, ProjectedPlaneBearing

    s = DoaSensor3D("a", sigma=SIG)
    p = np.array([3.0, 4.0, 5.0])
    z = np.array(s.angles(p))
    parts = np.array([[3.0, 4.0, 0, 0], [3.0, 5.0, 0, 0], [4.0, 3.0, 0, 0]])
    ll = ProjectedPlaneBearing(s, "xy").log_likelihood(z, parts)
    assert ll[0] == pytest.approx(0.0, abs=1e-20) and ll[1] < 0 and ll[2] < 0
    assert ProjectedPlaneBearing(s, "yz").variance(z) > 0
    cone = DoaCone(s).log_likelihood(z, np.array([[*p, 0, 0, 0], [*(2 * p), 0, 0, 0]]))
    assert cone == pytest.approx([0.0, 0.0], abs=1e-20)  # a cone: the whole ray is as likely
    with pytest.raises(ConfigError):
        ProjectedPlaneBearing(s, "xz")
