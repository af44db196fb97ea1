"""Two-sensor CRLB of the direct 3-D filter (Lee 2009, Scenario 4): information adds per sensor."""

import math

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.evaluation.projected_planes_crlb import direct3d_crlb
from fusetrack.experiments.lee2009.projected_planes import (
    AXES,
    SCN_ACCEL,
    SCN_DT,
    scenario_bounds,
    scenario_truth,
)
from fusetrack.motion.accel_turn import AccelTurn
from fusetrack.sensors.doa_projection import DoaSensor3D

SIG = math.radians(math.sqrt(3.0))


def test_the_same_sensor_twice_is_one_sensor_with_half_the_variance():
    truth = scenario_truth("S3")
    model = AccelTurn(3, SCN_ACCEL)
    s = DoaSensor3D("A0", (0.0, 0.0, 0.0), SIG)
    twice = direct3d_crlb(truth, [s, s], model, SCN_DT, sigma_pos=1e3, sigma_vel=1e3)
    half = DoaSensor3D("A0", (0.0, 0.0, 0.0), SIG / math.sqrt(2))
    np.testing.assert_allclose(
        twice, direct3d_crlb(truth, half, model, SCN_DT, sigma_pos=1e3, sigma_vel=1e3), rtol=1e-6
    )
    np.testing.assert_array_equal(
        direct3d_crlb(truth, [s], model, SCN_DT), direct3d_crlb(truth, s, model, SCN_DT)
    )
    with pytest.raises(ConfigError, match="sensor"):
        direct3d_crlb(truth, [], model, SCN_DT)


def test_scenario_4_bounds_use_both_sensors():
    b4 = scenario_bounds("S4")
    assert "y|yz@A1" in b4 and "x|3-D A0" in b4 and "y|yz@A1 switched" in b4
    for c in AXES:  # a second sensor can only add information to the 3-D bound
        assert np.all(b4[f"{c}|3-D"] <= b4[f"{c}|3-D A0"] + 1e-12)
    # primary-sensor 3-D bound of S4 is S3's (same object, same sensor)
    b3 = scenario_bounds("S3")
    for c in AXES:
        np.testing.assert_allclose(b4[f"{c}|3-D A0"], b3[f"{c}|3-D"], rtol=1e-9)
    # S4's PPS pairs: the first 13 instants as S3 (xy + yz of the primary), then zx@A0 + yz@A1
    np.testing.assert_allclose(b4["x|PPS"][:13], b3["x|PPS"][:13], rtol=1e-9)
