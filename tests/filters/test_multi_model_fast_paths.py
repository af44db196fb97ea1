"""The fast paths of Lee 2009's multi-model bearing PF equal their straightforward references.

* :func:`take_resampled` (a Numba gather) gives what ``np.take_along_axis`` gives;
* the filter's cached ``bank`` is :func:`kernel_bank` of its models, and read-only;
* :meth:`MultiModelBearingPF.step_bearings` on an array is :meth:`step` on measurements;
* the fused kernel's noise scaling and its skipped ``sin``/``cos`` at a zero turn rate leave
  the step equal to the NumPy reference (same draws).
"""

import math

import numpy as np
import pytest

from fusetrack.core import Measurement, MeasurementError
from fusetrack.filters import MultiModelBearingPF, finite_bearings, take_resampled, turn_models
from fusetrack.filters.multi_model_kernel import kernel_bank
from fusetrack.filters.multi_model_pf import weigh_every_model


def test_take_resampled_equals_take_along_axis():
    pred = np.arange(2 * 3 * 2 * 4 * 4, dtype=float).reshape(2, 3, 2, 4, 4)  # (B, O, J, L, 4)
    idx = np.array(
        [
            [[0, 7, 7, 3], [1, 1, 1, 1], [4, 5, 6, 7]],
            [[7, 6, 5, 4], [0, 0, 3, 4], [2, 2, 2, 2]],
        ]
    )
    want = np.take_along_axis(pred.reshape(2, 3, -1, 4), idx[..., None], axis=2)
    got = take_resampled(pred, idx)
    assert got.shape == (2, 3, 4, 4)
    assert np.array_equal(got, want)
    # a hand-checked entry: run 1, object 0, slot 0 takes model 1, particle 3
    assert np.array_equal(got[1, 0, 0], pred[1, 0, 1, 3])


def test_bank_is_kernel_bank_and_read_only():
    filt = MultiModelBearingPF(turn_models(1.0, 0.01), (0.0, 0.0), 0.05, 10)
    assert np.array_equal(filt.bank, kernel_bank(filt.models))
    assert np.array_equal(filt.bank, [0.0, -1.0, 1.0])
    assert filt.bank is filt.bank
    assert not filt.bank.flags.writeable


def test_kernel_equals_reference_with_standing_and_moving_particles():
    models = turn_models(0.5, 0.02)
    rng = np.random.default_rng(4)
    parts = rng.normal([20.0, 5.0, 0.3, -0.1], [1.0, 1.0, 0.2, 0.2], (2, 2, 30, 4))
    parts[0, 0, :5, 2:] = 0.0  # speed 0: the CV and both turns use omega = 0
    z = np.array([[0.2, 0.3], [0.25, -1.0]])
    out = {}
    for engine in ("numba", "numpy"):
        filt = MultiModelBearingPF(models, (0.0, 0.0), math.radians(3.0), 30, engine=engine)
        out[engine] = weigh_every_model(filt, parts, z, 1.0, np.random.default_rng(9))
    for a, b in zip(out["numba"][:3], out["numpy"][:3]):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    assert out["numba"][3] == out["numpy"][3]


def test_step_bearings_is_step_on_one_measurement_per_bearing():
    z = np.array([0.4, -0.2, 1.1])
    ms = [Measurement(3.0, "acoustic", v) for v in z]
    for estimator in ("consistent", "literal"):
        filt = MultiModelBearingPF(turn_models(1.0, 0.01), (0.0, 0.0), 0.05, 40, estimator)
        b0 = filt.initial_belief(
            np.array([10.0, 5.0, 0.2, 0.1]), np.full(4, 0.1), np.random.default_rng(1)
        )
        a = filt.step(b0, 1.0, ms, np.random.default_rng(2))
        b = filt.step_bearings(b0, 1.0, finite_bearings(z), np.random.default_rng(2))
        assert np.array_equal(a.states, b.states) and np.array_equal(a.mean, b.mean)
    with pytest.raises(MeasurementError, match="bearings"):
        finite_bearings([0.1, np.nan])
