"""Issue 4, bad input on the tracker side: each case gives a clear error or a documented result,
never NaN weights (camera behind a wall, a field of view with nothing in it, singular occluder
priors, a non-simple room)."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Measurement
from fusetrack.core.errors import ConfigError
from fusetrack.experiments.ercan2013.scenes import scene_from_mapping, square_scene
from fusetrack.filters.waypoint_asir import WaypointASIR
from fusetrack.sensors.occlusion_aware_camera import (
    CameraNetworkReport,
    OcclusionAwareCameraSensor,
    OcclusionAwareLikelihood,
)
from fusetrack.sensors.perspective_camera import ring_of_cameras
from fusetrack.world.occlusion import OccluderPriors
from fusetrack.world.room import Room

NOISE = {"sigma_theta": 0.01, "sigma_pos": 1.0, "sigma_read": 2.0}


def _room() -> Room:
    return square_scene(False).room


def test_camera_behind_a_wall_is_refused_by_the_likelihood():
    """A convex room does not test its walls for sight, so a camera outside would see through
    them: the likelihood refuses it, naming the camera."""
    cams = ring_of_cameras([(0, 0), (130, 50)], [45, 180], 90.0, **NOISE)
    with pytest.raises(ConfigError, match=r"camera position.*2"):
        OcclusionAwareLikelihood(cams, _room(), 3.33, "none")
    inside_occluder = ring_of_cameras([(0, 0), (50, 50)], [45, 0], 90.0, **NOISE)
    with pytest.raises(ConfigError, match="camera position"):
        OcclusionAwareLikelihood(inside_occluder, square_scene(True).room, 3.33, "none")


def test_non_simple_room_is_refused_before_any_tracking():
    with pytest.raises(ConfigError, match=r"room\.boundary"):
        Room(np.array([[0.0, 0.0], [100.0, 60.0], [100.0, 0.0], [0.0, 60.0]]))
    with pytest.raises(ConfigError, match=r"room\.boundary"):
        scene_from_mapping(
            {
                "room": [[0, 0], [100, 60], [100, 0], [0, 60]],
                "cameras": [{"position": [1, 1], "yaw": 45}],
            }
        )


@pytest.mark.parametrize("prior", ["gaussian", "perfect", "none"])
def test_camera_seeing_nothing_is_harmless_when_silent_and_ignored_when_it_reports(prior):
    """Camera 2 stands in a corner facing the walls: its view holds no particle. Its NaN readings
    leave the likelihood unchanged; a reading from it makes every particle impossible, and the ASIR
    then ignores the step (counted) with finite, normalised weights."""
    cams = ring_of_cameras([(0, 0), (0.5, 0.5)], [45, 225], 90.0, **NOISE)
    lik = OcclusionAwareLikelihood(cams, _room(), 3.33, prior, floor=1e-3, exclusion=3.33)
    rng = np.random.default_rng(1)
    x = rng.uniform(1, 99, (300, 2))
    occ: OccluderPriors | np.ndarray | None
    occ = {
        "gaussian": OccluderPriors(rng.uniform(0, 100, (15, 2)), 9.0 * np.eye(2)),
        "perfect": rng.uniform(0, 100, (15, 2)),
        "none": None,
    }[prior]
    z1 = float(cams.subset([0]).image_coordinate(np.array([40.0, 60.0]))[0])
    alone = lik.log_likelihood([z1], [0], x, occ)
    with_blind = lik.log_likelihood([z1, np.nan], [0, 1], x, occ)
    assert not np.isnan(with_blind).any()
    np.testing.assert_allclose(with_blind, alone)
    impossible = lik.log_likelihood([z1, 3.0], [0, 1], x, occ)
    assert np.all(impossible == -np.inf)

    asir = WaypointASIR(_room(), n_particles=200, sensors=(OcclusionAwareCameraSensor(lik),))
    b0 = asir.initialize(rng)
    report = CameraNetworkReport(np.array([z1, 3.0]), np.array([0, 1]), occ)
    b1 = asir.step(b0, 1.0, [Measurement(1.0, "cameras", report)], np.random.default_rng(2))
    assert np.all(np.isfinite(b1.weights)) and b1.weights.sum() == pytest.approx(1.0)
    assert np.all(np.isfinite(b1.particles)) and b1.ignored == 1 and b0.ignored == 0
    assert asir.stats.ignored_steps == 1 and asir.stats.first_stage_fallbacks == 1


@pytest.mark.parametrize(
    "cov",
    [
        np.zeros((2, 2)),  # a point: the occluder's position is known exactly
        np.array([[16.0, 16.0], [16.0, 16.0]]),  # a line: rank one
        np.diag([25.0, 0.0]),
    ],
)
def test_singular_occluder_covariance_gives_finite_likelihoods(cov):
    """Singular priors are regularised (eigenvalues floored at 1e-9): probabilities stay in [0, 1],
    the fused kernel agrees with the NumPy reference, and only impossible particles get -inf.
    (With floor 0 a line prior crossing several sight lines puts p(eta | u) on the clamp of Eq. 8,
    where the kernel's 3e-7 cut-offs can decide between 0 and a tiny p; the floor removes that.)"""
    sc = square_scene(False)
    lik = OcclusionAwareLikelihood(sc.cameras, sc.room, 3.33, "gaussian", floor=1e-3)
    rng = np.random.default_rng(3)
    pri = OccluderPriors(rng.uniform(10, 90, (12, 2)), np.broadcast_to(cov, (12, 2, 2)).copy())
    assert np.all(np.linalg.eigvalsh(pri.cov) > 0)
    x = rng.uniform(1, 99, (400, 2))
    sel = np.array([0, 6, 4, 2])
    truth = np.array([[30.0, 70.0]])
    z = sc.cameras.subset(sel).image_coordinate(truth).reshape(-1).copy()
    z[1] = np.nan
    fast = lik.log_likelihood(z, sel, x, pri)
    ref = lik.log_likelihood_reference(z, sel, x, pri)
    assert not np.isnan(fast).any() and not np.isnan(ref).any()
    assert np.array_equal(np.isfinite(fast), np.isfinite(ref))
    ok = np.isfinite(ref)
    assert ok.any()
    np.testing.assert_allclose(fast[ok], ref[ok], rtol=1e-6, atol=1e-4)
