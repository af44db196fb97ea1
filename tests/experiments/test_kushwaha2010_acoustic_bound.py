"""Kushwaha 2010's bearing PCRB (issue 19): the hand-computed Fisher information of two bearing
arrays, the noise estimate without per-pass biases, the bearing errors of a synthetic packet,
and the comparison that leaves single-bearing ticks out."""

import numpy as np
import pytest

from fusetrack.evaluation import ClaimKinds
from fusetrack.experiments.kushwaha2010 import acoustic_bound as ab
from fusetrack.experiments.kushwaha2010.scene import Layout
from fusetrack.management import Packet

KINDS = ClaimKinds({"BP_*": "diagnostic"})
TWO_ARRAYS = Layout(audio=(("A1", 0.0, 0.0, 0.3), ("A2", 10.0, 0.0, -1.0)), video=())


def test_one_tick_bound_is_the_sum_of_the_two_bearings_information():
    """Static target at (3, 4), one tick: J = P0^-1 + sum_s u u^T / (sigma^2 r^2), u across the
    line of sight; the position block of J^-1 (the bearings carry nothing on the velocity)."""
    sigma = np.deg2rad(5.0)
    target = np.array([[3.0, 4.0]])
    B = ab.position_bound(
        TWO_ARRAYS,
        ab.BearingNoise(audio=sigma, video=np.nan),
        {"audio": target, "video": target},
        np.zeros(2),
        {"audio": np.ones((1, 2), bool)},
    )
    # by hand: sensor (0, 0): d = (3, 4), r^2 = 25, u = (-4, 3)/5;
    #          sensor (10, 0): d = (-7, 4), r^2 = 65, u = (-4, -7)/sqrt(65)
    J = np.eye(2) / 100.0
    J += np.outer([-4.0, 3.0], [-4.0, 3.0]) / 25.0 / (sigma**2 * 25.0)
    J += np.outer([-4.0, -7.0], [-4.0, -7.0]) / 65.0 / (sigma**2 * 65.0)
    np.testing.assert_allclose(B[0], np.linalg.inv(J), rtol=1e-10)


def test_unreported_bearings_add_nothing():
    target = np.array([[3.0, 4.0]])
    B = ab.position_bound(
        TWO_ARRAYS,
        ab.BearingNoise(audio=0.1, video=np.nan),
        {"audio": target},
        np.zeros(2),
        {"audio": np.zeros((1, 2), bool)},
    )
    np.testing.assert_allclose(B[0], ab.PRIOR_COV[:2, :2])


def test_past_bearings_lower_the_bound_below_the_last_ticks_alone():
    """A vehicle at 10 m/s past the two arrays: the bound at the last tick, with the past
    carried by the motion model, is below the one-tick bound of the last tick's bearings."""
    t = np.arange(8) * 0.25
    path = np.column_stack([2.0 + 10.0 * t, np.full_like(t, 6.0)])
    noise = ab.BearingNoise(audio=0.1, video=np.nan)
    velocity = np.array([10.0, 0.0])
    B = ab.position_bound(
        TWO_ARRAYS, noise, {"audio": path}, velocity, {"audio": np.ones((8, 2), bool)}
    )
    last = ab.position_bound(
        TWO_ARRAYS, noise, {"audio": path[-1:]}, velocity, {"audio": np.ones((1, 2), bool)}
    )
    assert np.trace(B[-1]) < 0.5 * np.trace(last[0])
    assert np.all(np.linalg.eigvalsh(last[0] - B[-1]) > 0)  # below in every direction


def test_robust_sigma_leaves_out_each_sensors_bias_over_its_pass():
    rng = np.random.default_rng(3)
    biases = np.array([0.3, -0.2, 0.05])
    passes = [biases + 0.02 * rng.standard_normal((400, 3)) for _ in range(3)]
    passes[0][::50] = 2.0  # gross errors: left out by the median
    assert ab.robust_sigma(passes) == pytest.approx(0.02, rel=0.05)
    assert np.isnan(ab.robust_sigma([np.full((3, 2), np.nan)]))


def test_audio_doa_error_is_the_strongest_beam_minus_the_true_bearing():
    values = np.ones(36)
    values[4] = 5.0  # beam 4: 40 degrees from the heading
    taken = [{"A1": Packet("A1", 0, 0.0, values, 0.0)}]
    source = np.array([[np.cos(0.5), np.sin(0.5)]]) * 7.0  # at 0.5 rad from A1 at (0, 0)
    err = ab.audio_doa_errors(TWO_ARRAYS, taken, source)
    assert err[0, 0] == pytest.approx(0.3 + ab.BEAM_ANGLES[4] - 0.5)
    assert np.isnan(err[0, 1])  # no packet of A2


def test_video_bearing_error_is_the_nearest_component_of_a_vehicle_in_view():
    """One camera at the origin looking along +x: a blob on bins 80-84 points at bin 82's
    angle; a vehicle 0.01 rad off it is in error by -0.01 rad; a vehicle behind the camera has
    no bearing, nor, with ``apart``, two vehicles closer than it in view."""
    camera = Layout(audio=(), video=(("V1", 0.0, 0.0, 0.0),))
    values = np.zeros(160)
    values[80:85] = 50.0
    taken = [{"V1": Packet("V1", 0, 0.0, values, 0.0)}]
    a = ab.VIDEO_ANGLES[82] + 0.01
    centres = np.array([[[10 * np.cos(a), 10 * np.sin(a)], [-10.0, 0.0]]])  # (T=1, n=2, 2)
    err = ab.video_bearing_errors(camera, taken, centres)
    assert err.shape == (1, 1, 2)
    assert err[0, 0, 0] == pytest.approx(-0.01, abs=1e-9)
    assert np.isnan(err[0, 0, 1])  # behind the camera
    near = np.array([[[10 * np.cos(a), 10 * np.sin(a)], [10.0, 10 * np.tan(a + 0.02)]]])
    merged = ab.video_bearing_errors(camera, taken, near, apart=0.05)
    assert np.isnan(merged).all()


def test_comparison_keeps_only_ticks_with_two_bearings():
    B = np.stack([np.eye(2) * v for v in (100.0, 1.0, 4.0)])
    pb = ab.PassBound(B, np.array([False, True, True]))
    rms, mean_bound, rms_bound = pb.over([0, 1, 2], [9.0, 1.0, 3.0])
    assert rms == pytest.approx(np.sqrt((1.0 + 9.0) / 2))
    assert rms_bound == pytest.approx(np.sqrt((2.0 + 8.0) / 2))
    assert mean_bound == pytest.approx(np.sqrt(np.pi / 2) * 1.5)  # E|N(0, s^2 I)| = s sqrt(pi/2)
    assert all(np.isnan(pb.over([0], [1.0])))


def test_claims_fail_below_the_bound():
    below = ab.bound_row([0.5, 0.6], [0.8, 0.9], [1.0, 1.1])
    above = ab.bound_row([1.5, 1.6], [0.8, 0.9], [1.0, 1.1])
    assert not ab.above_bound_claim(KINDS, "BP_x", "x", {"a": above, "b": below}).holds
    assert ab.above_bound_claim(KINDS, "BP_x", "x", {"a": above}).holds
    judged = ab.paper_possible_claims(
        KINDS, "BP_t", "t", {"A": 0.5, "V": 2.0}, {"A": 1.0, "V": 1.0}
    )
    assert [c.holds for c in judged] == [False, True]
    assert [c.kind for c in judged] == ["diagnostic"] * 2
