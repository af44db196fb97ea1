"""Smart-camera trackers T0-T4 and P on rendered frames (Kushwaha 2010, Ch. V)."""

from functools import lru_cache

import numpy as np
import pytest

from fusetrack.core import Filter, GaussianMixture, Measurement, filter_step
from fusetrack.core.errors import MeasurementError
from fusetrack.filters.smart_camera_trackers import (
    CameraNetwork,
    ImagePlaneTracker,
    Particle3DTracker,
    RayIntersectionTracker,
    TrackerSettings,
    closed_form_map,
    fuse_orientation,
    hops,
    map_estimate,
    routing_tree,
    wahba_rotation,
)
from fusetrack.perception.appearance import appearance_model_from_views, features_from_rgb
from fusetrack.sensors.ellipsoid_camera import axis_angle_quaternion, quaternion_to_rotation
from fusetrack.world.ellipsoid_scene import (
    EllipsoidTarget,
    corner_cameras,
    cube_viewpoints,
    reference_views,
    render_frames,
    smooth_trajectory,
)

STEPS = 10


@lru_cache(maxsize=1)
def _scene():
    target = EllipsoidTarget()
    views = cube_viewpoints()
    model = appearance_model_from_views(*reference_views(target, views), views)
    cams = corner_cameras(focal=200.0)
    rng = np.random.default_rng(11)
    truth = smooth_trajectory(rng, STEPS, (1.5, 1.5, 0.6), (6.5, 6.5, 2.0), turn_sd=0.5)
    frames = render_frames(cams, target, truth, rng)
    hidden = np.ones((STEPS, len(cams)), bool)
    empty = render_frames(cams, target, truth, np.random.default_rng(11), hidden=hidden)
    net = CameraNetwork.build(cams, model, target.semi_axes, (0.0, 0.0, 0.0))

    def measurements(images):
        return [
            net.measurements(float(t), [features_from_rgb(i) for i in row])
            for t, row in enumerate(images)
        ]

    return truth, measurements(frames.images), measurements(empty.images), net


def _run(tracker, frames, truth, seed=0):
    """Errors and beliefs at steps 1..STEPS-1 from the true state at step 0."""
    rng = np.random.default_rng(seed)
    belief = tracker.initial_belief(*_init(truth), frames[0])
    errs, beliefs = [], []
    for t in range(1, STEPS):
        belief = filter_step(tracker, belief, 1.0, frames[t], rng)
        beliefs.append(belief)
        errs.append(np.linalg.norm(belief.position - truth.positions[t]))
    return np.array(errs), beliefs


def _init(truth):
    return truth.positions[0], truth.velocities[0], truth.quaternions[0]


def test_t0_tracks_an_easy_sequence_and_a_blind_one_drifts():
    truth, feats, blank, net = _scene()
    s = TrackerSettings(n_particles=300)
    err, beliefs = _run(Particle3DTracker("T0", net, s), feats, truth)
    assert err.mean() < 0.10
    # the same tracker on frames without the target (a likelihood that carries no information)
    err_blind, _ = _run(Particle3DTracker("T0", net, s), blank, truth)
    assert err_blind.mean() > 2 * err.mean()
    # bandwidth: C = 80 + 8 M N bytes per step (Sec. T0, [L2341])
    for b in beliefs:
        assert b.sent.bytes_sent == 80 + 8 * 300 * b.sent.cameras_used
        assert b.particles is not None and b.particles.n == 300


@pytest.mark.parametrize("mode", ["T1", "T2", "T3", "T4", "P"])
def test_other_trackers_follow_the_target_and_send_small_messages(mode):
    truth, feats, _, net = _scene()
    s = TrackerSettings(n_particles=300, n_particles_2d=100)
    if mode in ("T1", "T2"):
        tracker = Particle3DTracker(mode, net, s)
    elif mode in ("T3", "T4"):
        tracker = ImagePlaneTracker(mode, net, s)
    else:
        tracker = RayIntersectionTracker(net, s)
    err, beliefs = _run(tracker, feats, truth)
    assert np.all(np.isfinite(err))
    assert err.mean() < 0.25
    assert max(b.sent.bytes_sent for b in beliefs) < 0.1 * (80 + 8 * 1000 * 4)


def test_lost_target_never_gives_nan():
    truth, _, blank, net = _scene()
    s = TrackerSettings(n_particles=100, n_particles_2d=50)
    for tracker in (
        Particle3DTracker("T2", net, s),
        ImagePlaneTracker("T4", net, s),
        RayIntersectionTracker(net, s),
    ):
        err, _ = _run(tracker, blank, truth)
        assert np.all(np.isfinite(err))


def test_map_of_noise_free_image_mixtures_and_corrected_eq103():
    _, _, _, net = _scene()
    cams = list(net.cameras)
    x = np.array([4.2, 3.7, 1.3])
    x0 = x + np.array([0.12, -0.08, 0.05])
    gms = [
        GaussianMixture(np.array([1.0]), c.project(x)[None], np.eye(2)[None] * 2.0) for c in cams
    ]
    prior = 0.15**2 * np.eye(3)
    assert np.linalg.norm(map_estimate(cams, gms, x0, prior) - x) < 0.01
    one_step = closed_form_map(cams, gms, x0, prior)
    assert np.linalg.norm(one_step - x) < 0.5 * np.linalg.norm(x0 - x)


def test_wahba_recovers_orientation_and_the_fusion_keeps_unit_norm():
    rng = np.random.default_rng(2)
    q = axis_angle_quaternion([0.2, -0.5, 1.0], 1.3)
    R = quaternion_to_rotation(q)
    body = rng.normal(size=(4, 3))
    body /= np.linalg.norm(body, axis=1, keepdims=True)
    np.testing.assert_allclose(wahba_rotation(body, body @ R.T, np.ones(4)), R, atol=1e-10)
    views = [(b, R @ b, 1.0) for b in body]
    fused = fuse_orientation(views, np.array([0, 0, 0, 1.0]), alpha=1.0)
    assert abs(abs(fused @ q) - 1.0) < 1e-9
    half = fuse_orientation(views, np.array([0, 0, 0, 1.0]), alpha=0.3, method="paper")
    assert np.isclose(np.linalg.norm(half), 1.0)


def test_routing_tree_reaches_the_base():
    pos = np.array([[0, 0, 3.0], [8, 0, 3], [8, 8, 3], [0, 8, 3]])
    parent = routing_tree(pos, np.zeros(3))
    assert parent[0] == -1
    assert sorted(hops(parent, n) for n in range(4)) == [1, 2, 2, 3]


@pytest.mark.parametrize(("cls", "mode"), [(Particle3DTracker, "T3"), (ImagePlaneTracker, "T0")])
def test_a_mode_of_another_family_is_refused(cls, mode):
    from fusetrack.core.errors import ConfigError

    *_, net = _scene()
    with pytest.raises(ConfigError, match="mode"):
        cls(mode, net)


@pytest.mark.parametrize("mode", ["T0", "T2", "T4", "P"])
def test_trackers_are_pure_filters(mode):
    """A Filter: the same belief and seed give the same answer twice, and the input belief is
    left as it was (everything carried lives in the returned belief)."""
    truth, feats, _, net = _scene()
    s = TrackerSettings(n_particles=100, n_particles_2d=50)
    tracker = {
        "T0": Particle3DTracker("T0", net, s),
        "T2": Particle3DTracker("T2", net, s),
        "T4": ImagePlaneTracker("T4", net, s),
        "P": RayIntersectionTracker(net, s),
    }[mode]
    assert isinstance(tracker, Filter)
    b0 = tracker.initial_belief(*_init(truth), feats[0])
    before = (b0.position.copy(), b0.quaternion.copy(), dict(b0.pixel_tracks))
    b1 = filter_step(tracker, b0, 1.0, feats[1], np.random.default_rng(3))
    b2 = filter_step(tracker, b0, 1.0, feats[1], np.random.default_rng(3))
    np.testing.assert_array_equal(b1.position, b2.position)
    np.testing.assert_array_equal(b1.quaternion, b2.quaternion)
    np.testing.assert_array_equal(b0.position, before[0])
    np.testing.assert_array_equal(b0.quaternion, before[1])
    assert dict(b0.pixel_tracks) == before[2]
    assert not np.array_equal(b1.position, b0.position)


def test_a_camera_without_its_frame_does_not_take_part():
    truth, feats, _, net = _scene()
    s = TrackerSettings(n_particles=100)
    tracker = Particle3DTracker("T0", net, s)
    b0 = tracker.predict(tracker.initial_belief(*_init(truth)), 1.0)
    full = tracker.update(b0, feats[1], np.random.default_rng(0))
    fewer = tracker.update(b0, feats[1][1:], np.random.default_rng(0))
    assert fewer.sent.cameras_used == full.sent.cameras_used - 1
    assert fewer.sent.bytes_sent == 80 + 8 * 100 * fewer.sent.cameras_used
    # no frame at all: nothing to fuse, the prediction stands
    none = tracker.update(b0, [], np.random.default_rng(0))
    np.testing.assert_array_equal(none.position, b0.position)
    with pytest.raises(MeasurementError, match="FeatureImage"):
        tracker.update(
            b0, [Measurement(1.0, net.sensors[0].sensor_id, [1.0])], np.random.default_rng(0)
        )


def test_run_filter_runs_a_camera_tracker_over_the_frame_stream():
    """The library's runner takes the tracker like any Filter: the same track as the loop."""
    from fusetrack.filters import run_filter

    truth, feats, _, net = _scene()
    tracker = Particle3DTracker("T1", net, TrackerSettings(n_particles=100))
    _, beliefs = _run(tracker, feats, truth, seed=5)
    stream = [m for t in range(1, STEPS) for m in feats[t]]
    prior = tracker.initial_belief(*_init(truth), feats[0])
    track = run_filter(tracker, prior, stream, rng=np.random.default_rng(5), t0=0.0)
    np.testing.assert_array_equal(track.times, np.arange(1.0, STEPS))
    np.testing.assert_array_equal(track.means, np.array([b.position for b in beliefs]))
