"""Bad configuration raises ConfigError naming the field."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.sensors import AzimuthPolar, Bearing, PositionFix, Range, RangeBearing

BAD: list[tuple[str, Callable[[], Any]]] = [
    ("sigma", lambda: Bearing("b", [0.0, 0.0], 0.0)),
    ("sigma", lambda: Bearing("b", [0.0, 0.0], -1.0)),
    ("sigma", lambda: Range("r", [0.0, 0.0], math.nan)),
    ("sigma_azimuth", lambda: AzimuthPolar("a", [0.0, 0.0, 0.0], -0.1, 0.1)),
    ("sigma_polar", lambda: AzimuthPolar("a", [0.0, 0.0, 0.0], 0.1, 0.0)),
    ("sigma_range", lambda: RangeBearing("rb", [0.0, 0.0], 0.0, 0.1)),
    ("sigma_bearing", lambda: RangeBearing("rb", [0.0, 0.0], 0.1, math.inf)),
    ("cov", lambda: PositionFix("t", [[1.0, 0.5], [0.4, 1.0]])),  # not symmetric
    ("cov", lambda: PositionFix("t", [[1.0, 2.0], [2.0, 1.0]])),  # not positive definite
    ("cov", lambda: PositionFix("t", [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])),  # not square
    ("cov", lambda: PositionFix("t", [[1.0, math.nan], [math.nan, 1.0]])),
    ("bias", lambda: PositionFix("t", np.eye(2), bias=[1.0, 2.0, 3.0])),
    ("position", lambda: PositionFix("t", np.eye(2), max_range=5.0)),  # reader position needed
    ("position", lambda: PositionFix("t", np.eye(2), position=[0.0, 0.0, 0.0])),
    ("position", lambda: Bearing("b", [0.0, 0.0, 0.0], 0.1)),
    ("position", lambda: AzimuthPolar("a", [0.0, 0.0], 0.1, 0.1)),
    ("position", lambda: Range("r", [0.0], 0.1)),
    ("position", lambda: Range("r", [[0.0, 1.0]], 0.1)),
    ("position", lambda: Range("r", [0.0, math.inf], 0.1)),
    ("fov", lambda: Bearing("b", [0.0, 0.0], 0.1, fov=0.0)),
    ("fov", lambda: Bearing("b", [0.0, 0.0], 0.1, fov=7.0)),
    ("fov", lambda: Bearing("b", [0.0, 0.0], 0.1, fov=-1.0)),
    ("max_range", lambda: Range("r", [0.0, 0.0], 0.1, max_range=0.0)),
    ("max_range", lambda: Range("r", [0.0, 0.0], 0.1, max_range=math.nan)),
    ("detection_prob", lambda: Bearing("b", [0.0, 0.0], 0.1, detection_prob=1.5)),
    ("detection_prob", lambda: Bearing("b", [0.0, 0.0], 0.1, detection_prob=-0.1)),
    ("heading", lambda: Bearing("b", [0.0, 0.0], 0.1, heading=math.nan)),
    ("position_index", lambda: Bearing("b", [0.0, 0.0], 0.1, position_index=(0, 1, 2))),
    ("position_index", lambda: AzimuthPolar("a", [0.0, 0.0, 0.0], 0.1, 0.1, position_index=(0, 1))),
    ("position_index", lambda: Bearing("b", [0.0, 0.0], 0.1, position_index=(1, 1))),
    ("position_index", lambda: Bearing("b", [0.0, 0.0], 0.1, position_index=(-1, 0))),
    ("position_index", lambda: PositionFix("t", np.eye(3), position_index=(0, 1))),
    ("sensor_id", lambda: Bearing("", [0.0, 0.0], 0.1)),
]


@pytest.mark.parametrize(("field", "make"), BAD, ids=[f"{f}-{i}" for i, (f, _) in enumerate(BAD)])
def test_bad_config_names_the_field(field: str, make: Callable[[], Any]) -> None:
    with pytest.raises(ConfigError, match=rf"\b{field}=") as info:
        make()
    assert "expected" in str(info.value)


def test_message_names_the_sensor() -> None:
    with pytest.raises(ConfigError, match=r"Bearing\('doa-3'\).*sigma=-1"):
        Bearing("doa-3", [0.0, 0.0], -1)


def test_valid_edge_values_are_accepted() -> None:
    Bearing("b", [0.0, 0.0], 0.1, fov=2 * math.pi, detection_prob=0.0, max_range=math.inf)
    Bearing("b", [0.0, 0.0], 0.1, fov=1e-3, detection_prob=1.0, max_range=1e-3)
    PositionFix("t", [[2.0]], position_index=(3,))
    s = Range("r", np.array([1, 2]), 1)  # integers are coerced
    assert s.sigma == 1.0 and np.asarray(s.position).dtype == float


def test_stored_arrays_are_read_only() -> None:
    s = PositionFix("t", np.eye(2), bias=[1.0, 2.0])
    for a in (s.position, s.noise_cov(), s.bias):
        with pytest.raises(ValueError, match="read-only"):
            a[0] = 5.0  # type: ignore[index]


def test_position_index_accepts_none_and_lists() -> None:
    assert Bearing("b", [0.0, 0.0], 0.1, position_index=None).position_index == (0, 1)  # type: ignore[arg-type]
    assert Bearing("b", [0.0, 0.0], 0.1, position_index=[3, 1]).position_index == (3, 1)  # type: ignore[arg-type]
    assert PositionFix("t", np.eye(3)).position_index == (0, 1, 2)
