"""Sensor geometry: hand-computed predictions, field of view, range limits, detection."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from fusetrack.core import SensorModel
from fusetrack.sensors import (
    AzimuthPolar,
    Bearing,
    PositionFix,
    Range,
    RangeBearing,
    SensorBase,
    wrap,
)


def all_sensors() -> list[SensorBase]:
    return [
        Bearing("b", [1.0, 2.0], 0.1),
        AzimuthPolar("ap", [0.0, 0.0, 1.0], 0.05, 0.08),
        Range("r", [1.0, 2.0], 0.5),
        Range("r3", [1.0, 2.0, 3.0], 0.5),
        RangeBearing("rb", [1.0, 2.0], 0.5, 0.1),
        PositionFix("tag", [[0.2, 0.05], [0.05, 0.1]]),
    ]


@pytest.mark.parametrize("sensor", all_sensors(), ids=lambda s: s.sensor_id)
def test_every_sensor_follows_the_protocol(sensor: SensorBase) -> None:
    assert isinstance(sensor, SensorModel)
    assert len(sensor.angular) == sensor.dim
    assert sensor.noise_cov().shape == (sensor.dim, sensor.dim)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sensor.sensor_id = "other"  # type: ignore[misc]


def test_hand_computed_range_and_bearing() -> None:
    # sensor at (1, 2), target at (4, 6): d = (3, 4), range 5, bearing atan2(4, 3)
    x = np.array([4.0, 6.0, 0.5, -0.5])
    assert Range("r", [1.0, 2.0], 1.0).predict(x) == pytest.approx([5.0])
    assert Bearing("b", [1.0, 2.0], 1.0).predict(x) == pytest.approx([math.atan2(4, 3)])
    rb = RangeBearing("rb", [1.0, 2.0], 1.0, 1.0)
    assert rb.predict(x) == pytest.approx([5.0, math.atan2(4, 3)])


def test_bearing_is_relative_to_heading_and_wrapped() -> None:
    b = Bearing("b", [0.0, 0.0], 0.1, heading=math.pi / 2)
    assert b.predict([0.0, 1.0]) == pytest.approx([0.0], abs=1e-15)
    assert b.predict([1.0, 0.0]) == pytest.approx([-math.pi / 2])
    # straight behind: pi relative to the heading wraps to -pi (the half-open [-pi, pi))
    assert b.predict([0.0, -1.0]) == pytest.approx([-math.pi])
    b0 = Bearing("b0", [0.0, 0.0], 0.1)
    assert b0.predict([-1.0, 0.0])[0] == -math.pi  # atan2(0, -1) = +pi wraps to -pi
    # heading 3 rad, target at bearing -3 rad: relative -6 rad wraps to 2*pi - 6
    b3 = Bearing("b3", [0.0, 0.0], 0.1, heading=3.0)
    assert b3.predict([math.cos(-3.0), math.sin(-3.0)]) == pytest.approx([2 * math.pi - 6.0])


def test_azimuth_polar_hand_computed() -> None:
    s = AzimuthPolar("ap", [1.0, 1.0, 1.0], 0.1, 0.1, heading=0.25)
    x = np.array([2.0, 2.0, 1.0 + math.sqrt(2.0), 0.0, 0.0, 0.0])  # d = (1, 1, sqrt 2)
    az, polar = s.predict(x)
    assert az == pytest.approx(math.pi / 4 - 0.25)
    assert polar == pytest.approx(math.pi / 4)
    # straight up, horizontal and straight down: polar 0, pi/2, pi
    ups = np.array([[1.0, 1.0, 5.0], [4.0, 1.0, 1.0], [1.0, 1.0, -2.0]])
    assert s.predict(ups)[:, 1] == pytest.approx([0.0, math.pi / 2, math.pi])


def test_position_fix_with_bias_and_index() -> None:
    tag = PositionFix("tag", np.eye(2), bias=[0.5, -1.0], position_index=(0, 2))
    assert tag.predict([1.0, 9.0, 3.0, 9.0]) == pytest.approx([1.5, 2.0])
    tag3 = PositionFix("tag3", np.diag([1.0, 2.0, 3.0]))
    assert tag3.position_index == (0, 1, 2)
    assert tag3.predict(np.arange(6.0)) == pytest.approx([0.0, 1.0, 2.0])


def test_non_default_position_index() -> None:
    # state [vx, x, vy, y]
    b = Bearing("b", [1.0, 2.0], 0.1, position_index=(1, 3))
    assert b.predict([9.0, 4.0, 9.0, 6.0]) == pytest.approx([math.atan2(4, 3)])


def test_batch_shapes() -> None:
    rng = np.random.default_rng(0)
    x = rng.normal(size=(3, 5, 4))
    for s in all_sensors():
        if s.sensor_id in ("ap", "r3"):
            continue
        assert s.predict(x).shape == (3, 5, s.dim)
        assert s.jacobian(x).shape == (3, 5, s.dim, 4)
        assert s.fisher_information(x).shape == (3, 5, 4, 4)
        assert s.detection_probability(x).shape == (3, 5)
        assert s.visible(x).shape == (3, 5)
        assert s.log_likelihood(s.predict(x[0, 0]), x).shape == (3, 5)


def test_field_of_view_and_max_range() -> None:
    s = RangeBearing(
        "rb", [0.0, 0.0], 0.1, 0.01, heading=math.pi / 2, fov=math.pi / 2, max_range=10.0
    )
    x = np.array(
        [
            [0.0, 5.0],  # dead ahead
            [4.0, 5.0],  # 38.7 deg right of the heading: inside the 45 deg half-width
            [6.0, 5.0],  # 50.2 deg right: outside
            [0.0, 10.0],  # exactly at max range: inside
            [0.0, 10.5],  # beyond max range
            [0.0, -5.0],  # behind
        ]
    )
    expected = [True, True, False, True, False, False]
    assert s.visible(x).tolist() == expected
    assert s.detection_probability(x).tolist() == [float(e) for e in expected]


def test_fov_wraps_across_pi() -> None:
    # looking along -x: targets at bearings +179 deg and -179 deg are both inside a 10 deg fov
    s = Bearing("b", [0.0, 0.0], 0.1, heading=math.pi, fov=math.radians(10))
    a = np.radians([179.0, -179.0, 170.0, 0.0])
    x = np.stack([np.cos(a), np.sin(a)], axis=-1)
    assert s.visible(x).tolist() == [True, True, False, False]


def test_detection_probability_scales_visibility() -> None:
    s = Range("r", [0.0, 0.0, 0.0], 0.1, detection_prob=0.3, max_range=2.0)
    p = s.detection_probability([[1.0, 0.0, 0.0], [0.0, 0.0, 3.0]])
    assert p.tolist() == [0.3, 0.0]


def test_max_range_on_3d_range() -> None:
    s = AzimuthPolar("ap", [0.0, 0.0, 0.0], 0.1, 0.1, max_range=1.0)
    assert s.visible([[0.0, 0.0, 0.9], [0.6, 0.6, 0.6]]).tolist() == [True, False]


def test_position_fix_reader_range() -> None:
    tag = PositionFix("tag", np.eye(2), position=[10.0, 0.0], max_range=3.0)
    assert tag.visible([[8.0, 0.0, 1.0, 1.0], [0.0, 0.0, 0.0, 0.0]]).tolist() == [True, False]


def test_wrap_is_half_open() -> None:
    a = np.array([math.pi, -math.pi, np.nextafter(-math.pi, -4.0), 3 * math.pi, 7.0, -7.0])
    w = wrap(a)
    assert np.all(w >= -math.pi)
    assert np.all(w < math.pi)
    assert np.allclose(np.exp(1j * w), np.exp(1j * a))
