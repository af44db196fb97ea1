"""Smart-camera trackers T0-T4 and P on rendered frames (Kushwaha 2010, Ch. V)."""

from functools import lru_cache

import numpy as np
import pytest

from fusetrack.core import GaussianMixture
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
from fusetrack.perception.appearance import AppearanceModel, FeatureImage
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
    model = AppearanceModel.from_views(*reference_views(target, views), views)
    cams = corner_cameras(focal=200.0)
    rng = np.random.default_rng(11)
    truth = smooth_trajectory(rng, STEPS, (1.5, 1.5, 0.6), (6.5, 6.5, 2.0), turn_sd=0.5)
    frames = render_frames(cams, target, truth, rng)
    hidden = np.ones((STEPS, len(cams)), bool)
    empty = render_frames(cams, target, truth, np.random.default_rng(11), hidden=hidden)
    feats = [[FeatureImage.from_rgb(i) for i in row] for row in frames.images]
    blank = [[FeatureImage.from_rgb(i) for i in row] for row in empty.images]
    net = CameraNetwork.build(cams, model, target.semi_axes, (0.0, 0.0, 0.0))
    return truth, feats, blank, net


def _run(tracker, feats, truth, seed=0):
    rng = np.random.default_rng(seed)
    errs, reps = [], []
    for t in range(1, STEPS):
        rep = tracker.step(feats[t], rng)
        reps.append(rep)
        errs.append(np.linalg.norm(rep.position - truth.positions[t]))
    return np.array(errs), reps


def _init(truth):
    return truth.positions[0], truth.velocities[0], truth.quaternions[0]


def test_t0_tracks_an_easy_sequence_and_a_blind_one_drifts():
    truth, feats, blank, net = _scene()
    s = TrackerSettings(n_particles=300)
    err, reps = _run(Particle3DTracker("T0", net, *_init(truth), s), feats, truth)
    assert err.mean() < 0.10
    # the same tracker on frames without the target (a likelihood that carries no information)
    err_blind, _ = _run(Particle3DTracker("T0", net, *_init(truth), s), blank, truth)
    assert err_blind.mean() > 2 * err.mean()
    # bandwidth: C = 80 + 8 M N bytes per step (Sec. T0, [L2341])
    for r in reps:
        assert r.bytes_sent == 80 + 8 * 300 * r.cameras_used


@pytest.mark.parametrize("mode", ["T1", "T2", "T3", "T4", "P"])
def test_other_trackers_follow_the_target_and_send_small_messages(mode):
    truth, feats, _, net = _scene()
    s = TrackerSettings(n_particles=300, n_particles_2d=100)
    if mode in ("T1", "T2"):
        tracker = Particle3DTracker(mode, net, *_init(truth), s)
    elif mode in ("T3", "T4"):
        tracker = ImagePlaneTracker(mode, net, *_init(truth), s)
    else:
        tracker = RayIntersectionTracker(net, *_init(truth), feats[0], s)
    err, reps = _run(tracker, feats, truth)
    assert np.all(np.isfinite(err))
    assert err.mean() < 0.25
    assert max(r.bytes_sent for r in reps) < 0.1 * (80 + 8 * 1000 * 4)


def test_lost_target_never_gives_nan():
    truth, _, blank, net = _scene()
    s = TrackerSettings(n_particles=100, n_particles_2d=50)
    for tracker in (
        Particle3DTracker("T2", net, *_init(truth), s),
        ImagePlaneTracker("T4", net, *_init(truth), s),
        RayIntersectionTracker(net, *_init(truth), blank[0], s),
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

    truth, _, _, net = _scene()
    with pytest.raises(ConfigError, match="mode"):
        cls(mode, net, *_init(truth))
