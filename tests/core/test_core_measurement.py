import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fusetrack.core import (
    ConfigError,
    Measurement,
    MeasurementError,
    Track,
    angle_diff,
    check_positive,
    group_by_time,
    order_by_time,
    wrap_angle,
)


def test_measurement_validates_fields():
    with pytest.raises(MeasurementError, match="time"):
        Measurement(float("nan"), "a", [1.0])
    with pytest.raises(MeasurementError, match="sensor_id"):
        Measurement(0.0, "", [1.0])
    with pytest.raises(MeasurementError, match=r"covariance.*\(\.\.\., 2, 2\)"):
        Measurement(0.0, "a", [1.0, 2.0], covariance=np.eye(3))
    m = Measurement(1, "a", [np.nan])
    assert not m.is_finite and m.time == 1.0


def test_order_policies():
    ms = [Measurement(1.0, "a", [0]), Measurement(0.5, "b", [0]), Measurement(2.0, "a", [0])]
    with pytest.raises(MeasurementError, match=r"time=0\.5"):
        order_by_time(ms)
    assert [m.time for m in order_by_time(ms, "reorder")] == [0.5, 1.0, 2.0]
    with pytest.raises(MeasurementError, match="policy"):
        order_by_time(ms, "shuffle")  # type: ignore[arg-type]


def test_group_by_time():
    ms = [Measurement(t, s, [0]) for t, s in [(0, "a"), (0, "b"), (1, "a"), (3, "c"), (3, "a")]]
    groups = [(t, [m.sensor_id for m in g]) for t, g in group_by_time(ms)]
    assert groups == [(0.0, ["a", "b"]), (1.0, ["a"]), (3.0, ["c", "a"])]


def test_track_shapes_checked():
    Track(np.arange(3.0), np.zeros((3, 4)), np.zeros((3, 4, 4)))
    with pytest.raises(ValueError, match=r"means\.shape"):
        Track(np.arange(3.0), np.zeros((2, 4)))


def test_check_positive_message_names_field():
    with pytest.raises(ConfigError, match=r"dt=-1 is invalid: expected a finite number > 0"):
        check_positive("dt", -1)


@given(st.floats(-1e6, 1e6), st.floats(-1e6, 1e6))
def test_angle_diff_in_range_and_consistent(a, b):
    d = angle_diff(a, b)
    assert -np.pi <= d < np.pi
    assert np.isclose(np.cos(d), np.cos(a - b), atol=1e-6)
    assert np.isclose(np.sin(d), np.sin(a - b), atol=1e-6)


def test_wrap_known_values():
    np.testing.assert_allclose(wrap_angle([np.pi - 0.01 + 0.02, -np.pi]), [-np.pi + 0.01, -np.pi])
    assert np.isclose(angle_diff(np.pi - 0.01, -np.pi + 0.01), -0.02)
