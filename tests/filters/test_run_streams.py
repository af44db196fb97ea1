"""Per-run generators inside one Numba loop (``run_streams``): the same numbers as NumPy's
generators, the same particles as the NumPy reference and as separate runs, bit for bit."""

from __future__ import annotations

import gc
import os
import subprocess
import sys

import numba
import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import (
    BootstrapFilter,
    fused,
    fused_update,
    kernels,
    rng_handles,
    run_streams,
)
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing


@numba.njit
def _draw(handles, normals, uniforms):  # pragma: no cover - jit
    for r in range(handles.shape[0]):
        bg = rng_handles._bitgen(handles[r])
        uniforms[r] = rng_handles.next_double(bg)
        for i in range(normals.shape[1]):
            normals[r, i] = rng_handles.random_standard_normal(bg)


@pytest.mark.parametrize("bitgen", [np.random.PCG64, np.random.Philox, np.random.MT19937])
def test_handles_draw_numpys_numbers_and_advance_the_generators(bitgen):
    gens = [np.random.Generator(bitgen(s)) for s in (3, 4, 5)]
    refs = [np.random.Generator(bitgen(s)) for s in (3, 4, 5)]
    normals, uniforms = np.empty((3, 5000)), np.empty(3)
    _draw(rng_handles.generator_handles(gens), normals, uniforms)
    for r, g in enumerate(refs):
        assert uniforms[r] == g.random()
        np.testing.assert_array_equal(normals[r], g.standard_normal(5000))
        assert gens[r].standard_normal() == g.standard_normal()  # the state moved on


def _case(rows, n, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.normal(0, 5, (rows, n, 4))
    w = rng.uniform(0, 1, (rows, n)) ** 4
    w /= w.sum(axis=1, keepdims=True)
    F = np.eye(4) + np.diag([1.0, 1.0], 2)
    G = np.linalg.cholesky(np.array([[2, 0, 1, 0], [0, 2, 0, 1], [1, 0, 1, 0], [0, 1, 0, 1.0]]))
    anc = rng.integers(0, n, (rows, n))
    mode = np.arange(rows) % 3  # KEEP, GATHER, SYSTEMATIC
    return x, w, F, G, anc, mode


@pytest.mark.parametrize("rows, n", [(3, 50), (70, 1000)])  # serial, threaded (>= 65536)
def test_linear_gaussian_runs_equals_reference(rows, n):
    x, w, F, G, anc, mode = _case(rows, n)
    gens = [np.random.default_rng([7, r]) for r in range(rows)]
    refs = [np.random.default_rng([7, r]) for r in range(rows)]
    got = run_streams.linear_gaussian_runs(rng_handles.RunStreams(gens), x, F, G, mode, w, anc)
    want = run_streams.linear_gaussian_runs_reference(refs, x, F, G, mode, w, anc)
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-12)
    for g, h in zip(gens, refs):  # every stream advanced exactly as the reference's
        assert g.random() == h.random()


def test_linear_gaussian_runs_does_not_depend_on_the_threads():
    x, w, F, G, anc, mode = _case(70, 1000)
    outs = []
    for threads in (1, numba.config.NUMBA_NUM_THREADS):
        numba.set_num_threads(threads)
        gens = [np.random.default_rng([8, r]) for r in range(70)]
        outs.append(
            run_streams.linear_gaussian_runs(rng_handles.RunStreams(gens), x, F, G, mode, w, anc)
        )
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    np.testing.assert_array_equal(outs[0], outs[1])


def test_missing_weights_or_ancestors_are_refused():
    x, w, F, G, anc, mode = _case(3, 10)
    streams = rng_handles.RunStreams([np.random.default_rng(r) for r in range(3)])
    with pytest.raises(ValueError, match="weights"):
        run_streams.linear_gaussian_runs(streams, x, F, G, mode, None, anc)
    with pytest.raises(ValueError, match="ancestors"):
        run_streams.linear_gaussian_runs(streams, x, F, G, mode, w, None)
    with pytest.raises(ValueError, match="distinct"):
        g = np.random.default_rng(0)
        run_streams.linear_gaussian_runs(rng_handles.RunStreams([g, g, g]), x, F, G, mode, w, anc)
    with pytest.raises(ValueError, match="mode"):
        run_streams.linear_gaussian_runs(streams, x, F, G, mode + 5, w, anc)


@pytest.mark.parametrize("resampler", ["systematic", "stratified"])
@pytest.mark.parametrize("runs, n", [(4, 200), (80, 1000)])  # serial and threaded kernels
def test_batch_of_runs_is_bit_identical_to_separate_runs(resampler, runs, n):
    sensors = [Bearing(f"s{i}", p, sigma=0.02) for i, p in enumerate([[0, 0], [400, 0]])]
    kw = {"n_particles": n, "resampler": resampler, "ess_threshold": 0.6}
    prior = Gaussian(np.array([150.0, 100.0, 1.5, 1.0]), np.diag([400.0, 400.0, 1.0, 1.0]))
    truth = np.random.default_rng(1).normal([150, 100], 10, (runs, 2))
    z = np.arctan2(truth[:, 1:2] - [[0, 0]], truth[:, :1] - [[0, 400]])  # (runs, 2)
    batch_pf = BootstrapFilter(ConstantVelocity(ndim=2, q=0.05), sensors, **kw)
    gens = [np.random.default_rng([9, r]) for r in range(runs)]
    p = batch_pf.initialize(prior, gens, (runs,))
    for k in range(4):
        ms = [
            Measurement(k + 1.0, s.sensor_id, z[:, i : i + 1] + 0.01 * k)
            for i, s in enumerate(sensors)
        ]
        p = batch_pf.update(batch_pf.predict(p, 1.0, gens), ms, gens)
    for r in range(0, runs, max(1, runs // 4)):
        pf = BootstrapFilter(ConstantVelocity(ndim=2, q=0.05), sensors, **kw)
        g = np.random.default_rng([9, r])
        q = pf.initialize(prior, g)
        for k in range(4):
            ms = [
                Measurement(k + 1.0, s.sensor_id, z[r, i : i + 1] + 0.01 * k)
                for i, s in enumerate(sensors)
            ]
            q = pf.update(pf.predict(q, 1.0, g), ms, g)
        np.testing.assert_array_equal(p.states[r], q.states)
        np.testing.assert_array_equal(p.log_weights[r], q.log_weights)
    assert batch_pf.stats.resample_count >= 3


def test_threaded_normalisation_of_a_batch_equals_each_row_alone():
    rng = np.random.default_rng(4)
    lw = rng.normal(0, 30, (70, 1000))  # 70 000 particles: the threaded twin
    lw[3] = -np.inf  # a degenerate row
    x = rng.normal(0, 1, (70, 1000, 4))
    got = kernels.normalize_with_mean(lw.copy(), lw.max(axis=1), x)
    for r in (0, 3, 69):
        one = kernels.normalize_with_mean(
            lw[r : r + 1].copy(), lw[r : r + 1].max(axis=1), x[r : r + 1]
        )
        for a, b in zip(got, one):
            np.testing.assert_array_equal(a[r], b[0])


def test_openmp_wait_policy_is_set_at_the_first_threaded_call_not_at_import():
    code = (
        "import os; os.environ.pop('OMP_WAIT_POLICY', None)\n"
        "import fusetrack.filters as f\n"
        "print(os.environ.get('OMP_WAIT_POLICY'))\n"
        "f.fused.threaded(None)\n"
        "print(os.environ.get('OMP_WAIT_POLICY'))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.stdout.split() == ["None", "PASSIVE"], out.stderr


def test_run_streams_keep_their_generators_alive():
    streams = rng_handles.RunStreams([np.random.default_rng(s) for s in (1, 2)])
    gc.collect()  # the list is gone; the generators must not be
    normals, uniforms = np.empty((2, 10)), np.empty(2)
    _draw(streams.handles, normals, uniforms)
    assert uniforms[1] == np.random.default_rng(2).random()
    assert streams.distinct


def test_one_generator_for_several_runs_takes_the_locked_numpy_path():
    g = np.random.default_rng(3)
    assert not rng_handles.RunStreams([g, g]).distinct
    sensors = [Bearing("s0", [0.0, 0.0], sigma=0.02)]
    pf = BootstrapFilter(ConstantVelocity(ndim=2, q=0.05), sensors, n_particles=50)
    prior = Gaussian(np.array([150.0, 100.0, 1.5, 1.0]), np.eye(4))
    p = pf.initialize(prior, [g, g], (2,))
    p = pf.update(pf.predict(p, 1.0, [g, g]), [Measurement(1.0, "s0", [[0.6], [0.6]])], [g, g])
    assert np.all(np.isfinite(p.states)) and not np.array_equal(p.states[0], p.states[1])


@numba.njit
def _exps(v, out):  # pragma: no cover - jit
    for i in range(v.shape[0]):
        out[i] = fused_update.exp_nonpositive(v[i])


def test_vectorised_exp_is_numpys_to_one_ulp_and_zero_below_minus_708():
    v = -np.random.default_rng(2).exponential(40.0, 200_000)
    v = np.concatenate([v, [0.0, -0.0, -1e-300, -0.5, -707.99, -708.0, -708.01, -800.0, -np.inf]])
    got = np.empty_like(v)
    _exps(v, got)
    ref = np.exp(v)
    ok = v >= -708.0
    assert np.all(np.abs(got[ok] - ref[ok]) <= np.spacing(ref[ok]))
    assert np.all(got[~ok] == 0.0) and got[v == 0.0].tolist() == [1.0, 1.0]


@pytest.mark.parametrize("rows, n", [(1, 300), (3, 5000), (70, 1000), (1, 70_000), (2, 66_000)])
def test_one_pass_update_equals_the_three_pass_references(rows, n):
    rng = np.random.default_rng(6)
    x = rng.normal([150.0, 100.0, 1.0, 1.0], [40.0, 40.0, 1.0, 1.0], (rows, n, 4))
    lw = np.log(rng.dirichlet(np.ones(n), rows))
    sensors = [Bearing("a", [0.0, 0.0], sigma=0.05), Bearing("b", [400.0, 0.0], sigma=0.05)]
    kinds = np.array([0, 0])
    params = np.stack([fused.sensor_params(*s.fused_likelihood()) for s in sensors])
    z = rng.uniform(0.2, 2.5, (rows, 2, 1))
    usable = np.ones((rows, 2), bool)
    usable[0, 1] = False
    got = fused_update.log_weight_update_rows(x, lw, kinds, params, z, usable)
    acc, maxima = fused.log_likelihood_sum(x, lw, kinds, params, z, usable)
    np.testing.assert_array_equal(got[5], maxima)  # the same likelihood code: the same bits
    ref = kernels.normalize_with_mean(acc.copy(), maxima[:, -1], x)  # NumPy's exp
    for a, b in zip(got[:5], ref):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-300)
    assert np.all(np.isfinite(got[3])) and np.all(got[3] <= n)


def test_chunked_update_of_large_runs_equals_the_per_run_update_bit_for_bit(monkeypatch):
    """From SPLIT_MIN particles the update runs as (run, chunk) work items; with the split moved
    up, the same rows take the per-run kernel: the chunks and their order are the same."""
    rng = np.random.default_rng(8)
    x = rng.normal([150.0, 100.0, 1.0, 1.0], [40.0, 40.0, 1.0, 1.0], (2, 70_000, 4))
    lw = np.log(rng.dirichlet(np.ones(70_000), 2))
    sensor = Bearing("a", [0.0, 0.0], sigma=0.05)
    args = (np.array([0]), fused.sensor_params(*sensor.fused_likelihood())[None])
    z, usable = np.full((2, 1, 1), 0.6), np.ones((2, 1), bool)
    chunked = fused_update.log_weight_update_rows(x, lw, *args, z, usable)
    monkeypatch.setattr(fused_update, "SPLIT_MIN", 10**9)
    per_run = fused_update.log_weight_update_rows(x, lw, *args, z, usable)
    for a, b in zip(chunked, per_run):
        np.testing.assert_array_equal(a, b)


def test_draw_with_a_repeated_child_stream_is_refused():
    g = np.random.default_rng(1)
    x = np.zeros((1, 8, 4))
    with pytest.raises(ValueError, match="more than once"):
        fused.linear_gaussian_draw(x, np.eye(4), np.eye(4), (g, g))
