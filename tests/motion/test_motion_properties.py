"""Property tests: every motion model keeps the leading (batch) shape and treats rows alike."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import array_shapes

from fusetrack.motion import (
    ConstantAcceleration,
    ConstantVelocity,
    CoordinatedTurn,
    CoordinatedTurnRate,
    MarkovSwitching,
    RandomWalk,
)

MODELS = [
    RandomWalk(1, 0.3),
    RandomWalk(3, 1.0),
    ConstantVelocity(1),
    ConstantVelocity(2, 0.5),
    ConstantVelocity(3, 2.0, "discrete"),
    ConstantAcceleration(2, 0.1),
    ConstantAcceleration(3, 0.1, "discrete"),
    CoordinatedTurn(0.2),
    CoordinatedTurnRate(1.0, 0.01),
]

lead_shapes = array_shapes(min_dims=0, max_dims=3, min_side=1, max_side=4)
dts = st.floats(min_value=1e-3, max_value=10.0)
FAST = settings(max_examples=30, deadline=None)


@FAST
@given(model=st.sampled_from(MODELS), lead=lead_shapes, dt=dts, seed=st.integers(0, 2**32 - 1))
def test_outputs_keep_leading_shape_and_rows_are_independent(model, lead, dt, seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(*lead, model.dim))
    if isinstance(model, CoordinatedTurnRate):
        x[..., 4] *= 0.5
    d = model.dim
    mean = model.mean(x, dt)
    jac = model.jacobian(x, dt)
    xn = model.sample(x, dt, rng)
    ld = model.log_density(xn, x, dt)
    assert mean.shape == (*lead, d) and xn.shape == (*lead, d)
    assert jac.shape == (*lead, d, d)
    assert np.shape(ld) == lead and np.all(np.isfinite(ld))
    assert model.noise_cov(dt).shape == (d, d)
    # the batch is the same computation row by row, up to the rounding of a batched matmul: an
    # output that cancels to ~0 (a mean entry of -2.6e-6 from O(1) terms; a log density near 0)
    # may differ in its last bits relative to itself, so the tolerance is on the summed terms
    flat_x, flat_xn = x.reshape(-1, d), xn.reshape(-1, d)
    k = int(rng.integers(flat_x.shape[0]))
    jac_k = model.jacobian(flat_x[k], dt)
    terms = float(np.abs(jac_k).max() * np.abs(flat_x[k]).sum())
    np.testing.assert_allclose(
        mean.reshape(-1, d)[k], model.mean(flat_x[k], dt), rtol=1e-12, atol=1e-14 * terms
    )
    np.testing.assert_allclose(jac.reshape(-1, d, d)[k], jac_k, rtol=1e-12)
    np.testing.assert_allclose(
        np.reshape(ld, -1)[k], model.log_density(flat_xn[k], flat_x[k], dt), rtol=1e-10, atol=1e-9
    )


@FAST
@given(lead=lead_shapes, dt=dts, seed=st.integers(0, 2**32 - 1), data=st.data())
def test_switching_outputs_take_the_broadcast_shape(lead, dt, seed, data):
    ms = MarkovSwitching(
        (ConstantVelocity(2, 0.5), CoordinatedTurnRate(0.5), RandomWalk(2, 0.1)),
        [[0.8, 0.1, 0.1], [0.1, 0.8, 0.1], [0.3, 0.3, 0.4]],
    )
    rng = np.random.default_rng(seed)
    # modes over a suffix of the leading axes (e.g. per particle, shared by runs)
    k = data.draw(st.integers(0, len(lead)))
    mode_shape = lead[len(lead) - k :]
    modes = rng.integers(0, 3, size=mode_shape)
    x = rng.normal(size=(*lead, 5)) * 0.5
    assert ms.mean(x, dt, modes).shape == (*lead, 5)
    xn = ms.sample(x, dt, rng, modes)
    assert xn.shape == (*lead, 5)
    assert ms.jacobian(x, dt, modes).shape == (*lead, 5, 5)
    ld = ms.log_density(xn, x, dt, modes)
    assert ld.shape == lead and np.all(np.isfinite(ld))
    assert ms.sample_modes(modes, rng).shape == mode_shape
    assert ms.noise_cov(dt, modes).shape == (*mode_shape, 5, 5)
