"""The fused kernel and the batched periodic runs of Lee 2009's camera cooperation.

* the Numba kernel reproduces the NumPy reference (same draws) in :func:`run_cooperation` and in
  :func:`run_periodic_batch`;
* the batch has the law of :func:`run_cooperation` with a periodic policy: mean RMS over
  independent runs agree within their Monte Carlo error.
"""

import math

import numpy as np

from fusetrack.filters.multi_model_pf import turn_models
from fusetrack.management.camera_triggering import (
    AcousticTracker,
    CooperationPolicy,
    run_cooperation,
    run_periodic_batch,
)

DEG = math.pi / 180
SIGMA = math.sqrt(5.0) * DEG
MODELS = turn_models(1.0, 0.01)
KW = dict(models=MODELS, dt=1.0, known_initial_velocity=True, init_velocity_std=0.02)


def _truth(steps=30):
    x = np.zeros((steps, 2, 4))
    x[0] = [[50.0, 30.0, -0.2, 0.1], [35.0, 50.0, 0.1, -0.2]]
    for k in range(1, steps):
        x[k] = x[k - 1]
        x[k, :, :2] += x[k - 1, :, 2:]
    return x


def test_kernel_equals_reference_in_run_cooperation():
    truth = _truth(12)
    present = np.ones(truth.shape[:2], bool)
    out = {
        e: run_cooperation(
            truth,
            present,
            present,
            (0.0, 0.0),
            SIGMA,
            CooperationPolicy.triggering(),
            np.random.default_rng(5),
            tracker=AcousticTracker(n_particles=60, engine=e, **KW),
        )
        for e in ("numba", "numpy")
    }
    np.testing.assert_allclose(out["numba"].estimates, out["numpy"].estimates, rtol=0, atol=1e-9)
    assert np.array_equal(out["numba"].fired, out["numpy"].fired)


def test_kernel_equals_reference_in_the_batch():
    truth = _truth(10)
    periods = np.array([1, 3, 0, 7])
    a, b = (
        run_periodic_batch(
            truth,
            (0.0, 0.0),
            SIGMA,
            periods,
            np.random.default_rng(2),
            tracker=AcousticTracker(n_particles=40, engine=e, **KW),
        )
        for e in ("numba", "numpy")
    )
    np.testing.assert_allclose(a.estimates, b.estimates, rtol=0, atol=1e-9)
    assert np.array_equal(
        a.camera_updates[:, :, 0],
        np.array([[k > 0 and k % p == 0 if p else False for p in periods] for k in range(10)]),
    )


def test_batch_has_the_law_of_run_cooperation():
    truth = _truth(30)
    present = np.ones(truth.shape[:2], bool)
    n, period = 24, 10
    single = np.array(
        [
            run_cooperation(
                truth, present, present, (0.0, 0.0), SIGMA, CooperationPolicy(period=period),
                np.random.default_rng(100 + r), tracker=AcousticTracker(n_particles=60, **KW),
            ).estimates
            for r in range(n)
        ]
    )  # fmt: skip
    rms_single = np.sqrt(np.sum((single[..., :2] - truth[None, ..., :2]) ** 2, -1).mean(1))
    batch = run_periodic_batch(
        truth,
        (0.0, 0.0),
        SIGMA,
        np.full(n, period),
        np.random.default_rng(7),
        tracker=AcousticTracker(n_particles=60, **KW),
    )
    rms_batch = batch.rms(truth)
    assert rms_batch.shape == (n, 2)
    for o in range(2):
        a, b = rms_single[:, o], rms_batch[:, o]
        se = math.sqrt(a.var(ddof=1) / n + b.var(ddof=1) / n)
        assert abs(a.mean() - b.mean()) < 4 * se + 0.02, (o, a.mean(), b.mean(), se)
    # and the camera period matters in the batch as it should: T_v = 1 is far better than none
    both = run_periodic_batch(
        truth, (0.0, 0.0), SIGMA, np.array([1] * 8 + [0] * 8), np.random.default_rng(8),
        tracker=AcousticTracker(n_particles=60, **KW),
    ).rms(truth)  # fmt: skip
    assert both[:8].mean() < 0.5 * both[8:].mean()


def test_sample_cov_is_numpy_cov_to_the_bit():
    from fusetrack.management.camera_triggering import _sample_cov

    pts = np.array([[1.0, 2.0], [3.0, -1.0], [0.5, 0.25], [2.0, 2.0]])
    d = pts - pts.mean(axis=0)
    hand = d.T @ d / 3.0
    np.testing.assert_allclose(_sample_cov(pts), hand, rtol=1e-15)
    rng = np.random.default_rng(3)
    pred = 1e3 * rng.standard_normal((3, 501, 4)) + 40.0  # strided (L, 2) views, as the trigger's
    for p in pred[..., :2]:
        assert np.array_equal(_sample_cov(p), np.cov(p.T))
