"""WaypointASIR as a SteppingFilter: Algorithm 1's step and SIR's update(predict) target the same
posterior; the step's likelihood comes from the sensors the measurements name."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from fusetrack.core import Measurement, SteppingFilter
from fusetrack.core.errors import ConfigError, MeasurementError, UnknownSensorError
from fusetrack.experiments.ercan2013.scenes import square_scene
from fusetrack.filters import run_filter
from fusetrack.filters.waypoint_asir import ASIRBelief, WaypointASIR
from fusetrack.sensors.occlusion_aware_camera import (
    CameraNetworkReport,
    OcclusionAwareCameraSensor,
    OcclusionAwareLikelihood,
)


@dataclass(frozen=True)
class _PositionFix:
    """A Gaussian fix of the position: ``z ~ N(x, sigma^2 I)``."""

    sigma: float
    sensor_id: str = "fix"

    def log_likelihood(self, z: np.ndarray, x: np.ndarray) -> np.ndarray:
        r = np.asarray(z) - x[:, :2]
        return np.asarray(-0.5 * np.sum(r * r, axis=-1) / self.sigma**2)


def _cloud(n: int, rng: np.random.Generator) -> ASIRBelief:
    """Particles around (40, 50) walking to (80, 50) at speed 1."""
    u = np.empty((n, 5))
    u[:, :2] = [40.0, 50.0] + 4.0 * rng.standard_normal((n, 2))
    u[:, 2:4] = [80.0, 50.0]
    u[:, 4] = 1.0
    return ASIRBelief(u, np.full(n, 1.0 / n))


def test_is_a_stepping_filter():
    assert isinstance(WaypointASIR(square_scene(False).room), SteppingFilter)


def test_step_and_update_of_predict_agree_on_the_posterior():
    """Two fixes (sigma = 2) at (44, 50) of a cloud predicted to ~(41, 50): the posterior mean
    and spread of the ASIR step equal those of update(predict) (N = 20000, mean ~43.67). An ASIR
    that forgot to divide by the first-stage likelihood counts the fixes twice (mean 43.79)."""
    room = square_scene(False).room
    fix = _PositionFix(2.0)
    asir = WaypointASIR(room, n_particles=20000, sensors=(fix, _PositionFix(2.0, "fix2")))
    z = [Measurement(1.0, "fix", [44.0, 50.0]), Measurement(1.0, "fix2", [44.0, 50.0])]
    prior = _cloud(20000, np.random.default_rng(0))
    a = asir.step(prior, 1.0, z, np.random.default_rng(1))
    b = asir.update(asir.predict(prior, 1.0, np.random.default_rng(2)), z)
    np.testing.assert_allclose(a.position, [43.67, 50.0], atol=0.1)
    np.testing.assert_allclose(a.mean[:2], b.mean[:2], atol=0.05)
    spread_a, spread_b = np.sqrt(np.diag(a.cov)[:2]), np.sqrt(np.diag(b.cov)[:2])
    np.testing.assert_allclose(spread_a, spread_b, rtol=0.05)
    assert asir.stats.steps == 2 and a.ignored == 0


def test_without_measurements_a_step_is_a_prediction():
    asir = WaypointASIR(square_scene(False).room, n_particles=50)
    b0 = _cloud(50, np.random.default_rng(0))
    stepped = asir.step(b0, 1.0, [], np.random.default_rng(3))
    predicted = asir.predict(b0, 1.0, np.random.default_rng(3))
    np.testing.assert_array_equal(stepped.particles, predicted.particles)
    np.testing.assert_array_equal(stepped.weights, b0.weights)
    assert asir.predict(b0, 0.0) is b0


def test_camera_report_travels_as_a_measurement_value():
    """The sensor reads readings, selected cameras and occluder knowledge from one value; the
    update weights the particles exactly by the likelihood of those arrays."""
    sc = square_scene(False)
    lik = OcclusionAwareLikelihood(sc.cameras, sc.room, 3.33, "none", floor=1e-3)
    asir = WaypointASIR(sc.room, n_particles=300, sensors=(OcclusionAwareCameraSensor(lik),))
    b0 = asir.initialize(np.random.default_rng(4))
    sel = np.array([0, 2])
    z = sc.cameras.subset(sel).image_coordinate(np.array([[30.0, 70.0]])).reshape(-1)
    report = Measurement(1.0, "cameras", CameraNetworkReport(z, sel))
    b1 = asir.update(b0, [report])
    ll = lik.log_likelihood(z, sel, b0.particles)
    expected = np.exp(ll - ll.max())
    np.testing.assert_allclose(b1.weights, expected / expected.sum(), rtol=1e-12)
    with pytest.raises(MeasurementError, match="CameraNetworkReport"):
        asir.update(b0, [Measurement(1.0, "cameras", z)])


def test_bad_input_names_the_field():
    asir = WaypointASIR(square_scene(False).room, n_particles=20, sensors=(_PositionFix(1.0),))
    b0 = _cloud(20, np.random.default_rng(0))
    with pytest.raises(UnknownSensorError, match=r"sensor_id='radar'.*fix"):
        asir.step(b0, 1.0, [Measurement(1.0, "radar", [1.0, 2.0])], np.random.default_rng(0))
    with pytest.raises(ConfigError, match="rng=None"):
        asir.step(b0, 1.0, [Measurement(1.0, "fix", [1.0, 2.0])])


def test_run_filter_tracks_a_walk_seen_by_four_cameras():
    """run_filter drives the ASIR over camera-network reports: the object walking from (31, 70)
    to (50, 70) is found (position error < 2 units after 20 steps from a uniform cloud)."""
    sc = square_scene(False)
    lik = OcclusionAwareLikelihood(sc.cameras, sc.room, 3.33, "none", floor=1e-3)
    asir = WaypointASIR(sc.room, n_particles=500, sensors=(OcclusionAwareCameraSensor(lik),))
    rng = np.random.default_rng(5)
    sel = np.array([0, 2, 4, 6])
    truth = np.column_stack([30.0 + np.arange(1, 21), np.full(20, 70.0)])
    z = sc.cameras.subset(sel).image_coordinate(truth[:, None, :])
    reports = [
        Measurement(float(t + 1), "cameras", CameraNetworkReport(z[t], sel)) for t in range(20)
    ]
    track = run_filter(asir, asir.initialize(rng), reports, rng=rng, t0=0.0)
    assert track.means.shape == (20, 5)
    assert np.linalg.norm(track.means[-1, :2] - truth[-1]) < 2.0
    assert track.info["stats"]["steps"] == 20
