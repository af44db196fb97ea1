"""The stacked sensor's vectorised Bearing bank equals the parts' own methods."""

from __future__ import annotations

import numpy as np

from fusetrack.sensors import Bearing, PositionFix, Range, StackedSensor


def _parts():
    rng = np.random.default_rng(3)
    bearings = [
        Bearing(f"b{i}", position=rng.uniform(-50, 50, 2), sigma=0.01 * (i + 1), heading=0.3 * i)
        for i in range(6)
    ]
    # mixed in: a position fix, a range and a bearing on other state entries (its own group)
    others = [
        PositionFix("tag", cov=np.diag([0.5, 2.0])),
        Range("r", position=[1.0, 2.0], sigma=0.5),
        Bearing("far", position=[0.0, 0.0], sigma=0.1, position_index=(2, 3)),
    ]
    return bearings[:3] + others[:1] + bearings[3:] + others[1:]


def test_bank_equals_the_parts_one_by_one():
    parts = _parts()
    s = StackedSensor("all", parts)
    assert len(s._banks) == 1 and s._banks[0].rows.tolist() == [0, 1, 2, 5, 6, 7]
    x = np.random.default_rng(0).normal(0, 30, (5, 4))
    np.testing.assert_array_equal(
        s.predict(x), np.concatenate([p.predict(x) for p in parts], axis=-1)
    )
    np.testing.assert_array_equal(
        s.jacobian(x), np.concatenate([p.jacobian(x) for p in parts], axis=-2)
    )
    z = s.predict(x) + 3.0  # residual wraps the angles, not the tag or the range
    ref = np.concatenate(
        [p.residual(a, b) for p, a, b in zip(parts, s._split(z), s._split(s.predict(x)))], -1
    )
    np.testing.assert_allclose(s.residual(z, s.predict(x)), ref, atol=1e-15)
    assert abs(s.residual(z, s.predict(x))[0, 0]) <= np.pi  # a bearing: wrapped
    np.testing.assert_allclose(s.residual(z, s.predict(x))[:, 3:5], 3.0)  # the tag: plain


def test_all_scalar_noise_is_the_diagonal():
    parts = [p for p in _parts() if p.dim == 1]
    s = StackedSensor("scalars", parts)
    np.testing.assert_array_equal(
        s.noise_cov(), np.diag([float(p.noise_cov()[0, 0]) for p in parts])
    )
