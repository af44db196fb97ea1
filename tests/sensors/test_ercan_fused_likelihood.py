"""The one-pass Numba camera-network likelihood against its NumPy reference, and its two corrections
to the printed model (the floor on p(eta | u) and the rectangles that stop short of the object)."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.experiments.ercan2013.scenes import get_scene
from fusetrack.experiments.ercan2013.simulation import world_and_readings
from fusetrack.sensors.occlusion_aware_camera import OcclusionAwareLikelihood
from fusetrack.sensors.perspective_camera import ring_of_cameras
from fusetrack.world.geometry import points_in_polygon
from fusetrack.world.occlusion import OccluderPriors, occlusion_probability_reference
from fusetrack.world.room import square_room

NOISE = {"sigma_theta": 0.01, "sigma_pos": 1.0, "sigma_read": 2.0}


@pytest.mark.parametrize("scene_name", ["square", "L"])
@pytest.mark.parametrize("floor, exclusion", [(0.0, 0.0), (1e-3, 3.33)])
def test_fused_kernel_equals_the_reference(scene_name: str, floor: float, exclusion: float) -> None:
    scene = get_scene(scene_name)
    obj, occ, z = world_and_readings(scene, 40, 40, 3)
    rng = np.random.default_rng(1)
    sel = np.arange(6)
    for t in (10, 35):
        x = obj[t] + rng.normal(0, 5, (300, 2))
        iso = OccluderPriors(occ[t] + rng.normal(0, 2, (40, 2)), np.eye(2) * 9.0)
        tilted = OccluderPriors(occ[t], np.array([[4.0, 1.0], [1.0, 2.0]]))
        for mode, occluders in (
            ("none", None),
            ("perfect", occ[t]),
            ("gaussian", iso),
            ("gaussian", tilted),
        ):
            lik = OcclusionAwareLikelihood(
                scene.cameras, scene.room, scene.diameter, mode, floor, exclusion
            )  # type: ignore[arg-type]
            fast = lik.log_likelihood(z[t, sel], sel, x, occluders)
            ref = lik.log_likelihood_reference(z[t, sel], sel, x, occluders)
            assert np.array_equal(np.isfinite(fast), np.isfinite(ref))
            ok = np.isfinite(ref)
            # table-lookup normal CDF and 5-sd cut-offs: probabilities agree to ~1e-6
            np.testing.assert_allclose(np.exp(fast[ok]), np.exp(ref[ok]), rtol=1e-3, atol=1e-9)


def test_isotropic_priors_row_path_equals_the_general_path_bit_for_bit() -> None:
    """With every prior isotropic the kernels compute q a sight line at a time (the SIMD row);
    one extra tilted occluder far outside the room forces the triple-by-triple path, adds q = 0
    everywhere, and must leave every value identical, not merely close."""
    from fusetrack.world.occlusion_kernels import occlusion_probability_kernel

    scene = get_scene("square")
    obj, occ, z = world_and_readings(scene, 40, 40, 3)
    rng = np.random.default_rng(2)
    sel = np.arange(6)
    cams = np.asarray(scene.cameras.positions, dtype=float)
    for t, sd in ((10, 1.5), (35, 7.3)):
        x = obj[t] + rng.normal(0, 4, (400, 2))
        mu = occ[t] + rng.normal(0, sd, (40, 2))
        far_mu = np.vstack([mu, [[1e5, 1e5]]])
        cov = np.eye(2)[None] * (sd * rng.uniform(0.5, 1.5, 41))[:, None, None] ** 2
        cov[40] = [[2.0, 0.5], [0.5, 1.0]]
        lik = OcclusionAwareLikelihood(
            scene.cameras, scene.room, scene.diameter, "gaussian", 1e-3, 3.33
        )
        row = lik.log_likelihood(z[t, sel], sel, x, OccluderPriors(mu, cov[:40]))
        general = lik.log_likelihood(z[t, sel], sel, x, OccluderPriors(far_mu, cov))
        assert np.isfinite(row).sum() > 100
        assert np.array_equal(row, general)
        q_row = occlusion_probability_kernel(cams, x, mu, cov[:40], scene.diameter, 3.33)
        q_general = occlusion_probability_kernel(cams, x, far_mu, cov, scene.diameter, 3.33)
        assert (q_row > 0).mean() > 0.05
        assert np.array_equal(q_row, q_general[:, :, :40]) and not q_general[:, :, 40].any()


def _cross_of_cameras() -> tuple[object, object]:
    cams = ring_of_cameras(
        [(0, 50), (50, 0), (100, 50), (50, 100)], [0, 90, 180, 270], 90.0, **NOISE
    )
    return cams, square_room(100.0, [])


def test_rectangles_meeting_at_the_object_no_longer_rule_out_the_truth() -> None:
    """Four cameras see the object at (50, 50); an occluder prior sits 1 unit from it (sd 1). All
    four rectangles of Eq. 7 contain that mass: sum_i q = 1.65 > 1, the clamped Eq. 8 factor is 0
    and the printed model gives the true position probability 0. Stopping the rectangles D before
    the object (where no occluder can stand) leaves sum_i q ~ 0.007 and a finite likelihood."""
    cams, room = _cross_of_cameras()
    x = np.array([[50.0, 50.0]])
    prior = OccluderPriors(np.array([[50.7, 50.7]]), np.eye(2)[None])
    q = occlusion_probability_reference(cams.positions, x, prior, 3.33)  # type: ignore[attr-defined]
    assert q.sum() == pytest.approx(1.647, abs=1e-3)
    q_short = occlusion_probability_reference(cams.positions, x, prior, 3.33, exclusion=3.33)  # type: ignore[attr-defined]
    assert q_short.sum() < 0.01
    z = cams.image_coordinate(x[:, None, :])[0]  # type: ignore[attr-defined]
    sel = np.arange(4)
    printed = OcclusionAwareLikelihood(cams, room, 3.33, "gaussian")  # type: ignore[arg-type]
    fixed = OcclusionAwareLikelihood(cams, room, 3.33, "gaussian", exclusion=3.33)  # type: ignore[arg-type]
    assert printed.log_likelihood(z, sel, x, prior)[0] == -np.inf
    assert np.isfinite(fixed.log_likelihood(z, sel, x, prior)[0])


def test_floor_keeps_inconsistent_particles_alive_but_never_impossible_ones() -> None:
    """Perfect priors: a particle that a disc hides from a camera that did see the object gets the
    floor (not 0); a particle outside a reporting camera's field of view stays impossible."""
    cams, room = _cross_of_cameras()
    sel = np.array([0])  # camera at (0, 50) looking along +x
    disc = np.array([[30.0, 50.0]])
    hidden, clear, behind = [60.0, 50.0], [60.0, 70.0], [-5.0, 50.0]
    x = np.array([hidden, clear, behind])
    z = cams.subset(sel).image_coordinate(np.array([[[60.0, 70.0]]]))[0]  # type: ignore[attr-defined]
    hard = OcclusionAwareLikelihood(cams, room, 3.33, "perfect")  # type: ignore[arg-type]
    soft = OcclusionAwareLikelihood(cams, room, 3.33, "perfect", floor=1e-3)  # type: ignore[arg-type]
    l_hard = hard.log_likelihood(z, sel, x, disc)
    l_soft = soft.log_likelihood(z, sel, x, disc)
    assert l_hard[0] == -np.inf and np.isfinite(l_hard[1]) and l_hard[2] == -np.inf
    assert l_soft[1] == pytest.approx(l_hard[1])
    assert l_soft[2] == -np.inf
    # the hidden particle keeps the Gaussian part of Eq. 6, scaled by the floor
    gauss_hidden = soft.log_likelihood(z, sel, x[:1], np.zeros((0, 2)))[0]
    assert l_soft[0] == pytest.approx(gauss_hidden + np.log(1e-3))


def test_numba_point_in_polygon_equals_the_numpy_one() -> None:
    rng = np.random.default_rng(0)
    for name in ("L", "square", "lab"):
        room = get_scene(name).room
        p = rng.uniform(-10, 270, (5000, 2))
        p[:200] = np.round(p[:200] / 50) * 50  # vertices and edges
        expected = points_in_polygon(p, room.boundary)
        for o in room.static_occluders:
            expected &= ~points_in_polygon(p, o)
        assert np.array_equal(room.free(p), expected)
        assert room.free(p.reshape(50, 100, 2)).shape == (50, 100)


def test_occlusion_power_scales_only_the_pattern_term() -> None:
    """log f = log G + gamma log p(eta | u): the kernel and the reference agree at gamma = 0.3, and
    log f(gamma = 1) - log f(gamma) = (1 - gamma) log p(eta | u) for every possible particle."""
    scene = get_scene("square")
    obj, occ, z = world_and_readings(scene, 40, 40, 3)
    rng = np.random.default_rng(2)
    sel = np.arange(5)
    t = 20
    x = obj[t] + rng.normal(0, 6, (400, 2))
    pri = OccluderPriors(occ[t] + rng.normal(0, 3, (40, 2)), np.eye(2) * 9.0)
    full = OcclusionAwareLikelihood(
        scene.cameras, scene.room, scene.diameter, "gaussian", 1e-3, 3.33
    )
    tempered = OcclusionAwareLikelihood(
        scene.cameras, scene.room, scene.diameter, "gaussian", 1e-3, 3.33, occlusion_power=0.3
    )
    a = full.log_likelihood(z[t, sel], sel, x, pri)
    b = tempered.log_likelihood(z[t, sel], sel, x, pri)
    ref = tempered.log_likelihood_reference(z[t, sel], sel, x, pri)
    ok = np.isfinite(a)
    assert ok.sum() > 50 and np.array_equal(ok, np.isfinite(b))
    np.testing.assert_allclose(b[ok], ref[ok], rtol=0, atol=1e-4)
    no_pattern = OcclusionAwareLikelihood(scene.cameras, scene.room, scene.diameter, "none")
    log_g = no_pattern.log_likelihood(z[t, sel], sel, x)
    log_p = a[ok] - log_g[ok]
    assert np.ptp(log_p) > 1.0  # the pattern term varies over the cloud
    np.testing.assert_allclose(a[ok] - b[ok], 0.7 * log_p, rtol=1e-9, atol=1e-9)
    with pytest.raises(Exception, match="occlusion_power"):
        OcclusionAwareLikelihood(scene.cameras, scene.room, 3.33, "gaussian", occlusion_power=0.0)


def test_camera_arrays_remembered_per_selection_give_the_same_likelihood() -> None:
    """The kernel's camera arrays are made once per distinct selection: alternating selections
    on one likelihood give bit for bit what a fresh likelihood gives for each."""
    scene = get_scene("L")
    obj, occ, z = world_and_readings(scene, 40, 20, 5)
    rng = np.random.default_rng(2)
    x = obj[12] + rng.normal(0, 6, (200, 2))
    pri = OccluderPriors(occ[12] + rng.normal(0, 2, (40, 2)), np.eye(2) * 16.0)
    lik = OcclusionAwareLikelihood(scene.cameras, scene.room, scene.diameter, "gaussian")
    selections = [np.array([0, 3, 5]), np.array([1, 2, 7, 9]), np.array([0, 3, 5])]
    got = [lik.log_likelihood(z[12, s], s, x, pri) for s in selections]
    for s, g in zip(selections, got, strict=True):
        fresh = OcclusionAwareLikelihood(scene.cameras, scene.room, scene.diameter, "gaussian")
        assert np.array_equal(g, fresh.log_likelihood(z[12, s], s, x, pri))
    assert np.array_equal(got[0], got[2])
    assert not np.array_equal(got[0], got[1])
    assert len(lik._camera_args) == 2


def test_bad_inputs_are_refused_naming_the_field() -> None:
    """Before the kernel: a camera index outside the network, an infinite reading (NaN means not
    seen and is fine), a NaN particle position and a NaN occluder centre are each a clear error,
    for the fused likelihood and its reference alike (a NaN position used to give NaN weights)."""
    from fusetrack.core import ConfigError, MeasurementError

    scene = get_scene("square")
    obj, occ, z = world_and_readings(scene, 40, 5, 3)
    sel = np.arange(4)
    x = obj[2] + np.zeros((5, 2))
    lik = OcclusionAwareLikelihood(scene.cameras, scene.room, scene.diameter, "perfect")
    n = len(scene.cameras.positions)
    for f in (lik.log_likelihood, lik.log_likelihood_reference):
        assert np.all(np.isfinite(f(z[2, sel], sel, x, occ[2])) | np.isnan(z[2, sel]).any())
        with pytest.raises(ConfigError, match=rf"selected=\[0, 1, {n}\] is invalid"):
            f(z[2, :3], [0, 1, n], x, occ[2])
        with pytest.raises(ConfigError, match="camera indices"):
            f(z[2, :1], [-1], x, occ[2])
        with pytest.raises(MeasurementError, match=r"z=.*finite readings, NaN where unseen"):
            f(np.r_[z[2, :3], np.inf], sel, x, occ[2])
        bad = x.copy()
        bad[3, 1] = np.nan
        with pytest.raises(ConfigError, match=r"x\[3\]=\[.*nan\] is invalid"):
            f(z[2, sel], sel, bad, occ[2])
        centres = occ[2].copy()
        centres[0, 0] = np.nan
        with pytest.raises(ConfigError, match=r"occluders\[0\]"):
            f(z[2, sel], sel, x, centres)
