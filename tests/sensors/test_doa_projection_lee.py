"""Lee 2009 Ch. 2 geometry: plane bearings, the closed-form projected variance, plane selection."""

import math

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError, MeasurementError
from fusetrack.sensors.doa_projection import (
    DoaSensor3D,
    check_angles,
    direction_angles,
    literal_second_plane,
    minvar_second_plane,
    monte_carlo_projected_variance,
    projected_angles,
    projected_variance,
)

D = math.pi / 180


def test_spec_reference_angles_are_polar():
    # spec Sec. 2: (3,3,1) -> 76.74 deg, (1,1,3) -> 25.24 deg, (10,130,18) -> 82.14 deg
    _, phi = direction_angles(np.array([[3, 3, 1], [1, 1, 3], [10, 130, 18]], float))
    assert np.degrees(phi) == pytest.approx([76.74, 25.24, 82.14], abs=0.01)


def test_plane_bearings_match_printed_formula_for_positive_x():
    rng = np.random.default_rng(1)
    th = rng.uniform(-80, 80, 50) * D  # x > 0
    ph = rng.uniform(5, 175, 50) * D
    a = projected_angles(th, ph)
    yz = np.arctan(np.abs(1 / np.cos(th)) / (np.tan(th) * np.tan(ph)))  # Eq. 2.1 before beta
    diff = np.mod(a[:, 1] - yz + math.pi / 2, math.pi) - math.pi / 2  # equal up to the beta branch
    assert np.allclose(diff, 0, atol=1e-9)
    assert np.allclose(a[:, 0], th)


@pytest.mark.parametrize(
    ("theta", "phi", "yz", "zx"),
    [(5, 10, 0.039, 0.993), (30, 60, 2.041, 1.207), (45, 45, 1.111, 1.111), (85, 80, 1.007, 26.0)],
)
def test_closed_form_matches_spec_table(theta, phi, yz, zx):
    v = projected_variance(theta * D, phi * D)
    assert v[0] == 1.0
    assert v[1] == pytest.approx(yz, rel=5e-3)
    assert v[2] == pytest.approx(zx, rel=5e-3)


@pytest.mark.parametrize(("theta", "phi"), [(30, 60), (60, 20), (120, 100), (250, 140)])
def test_closed_form_against_monte_carlo(theta, phi):
    rng = np.random.default_rng(7)
    n = 200_000
    mc = monte_carlo_projected_variance(theta * D, phi * D, D, n, rng) / D**2
    cf = projected_variance(theta * D, phi * D)
    # sampling error sqrt(2/n) ~ 0.3 %, delta-method bias ~ 1 % at sigma = 1 deg
    assert mc == pytest.approx(cf, rel=0.03)
    assert mc[0] == pytest.approx(1.0, rel=0.015)


def test_yz_smaller_only_outside_45_135():
    th = np.linspace(0, 2 * math.pi, 73)[:, None]
    inside = projected_variance(th, np.linspace(46, 134, 23)[None, :] * D)
    assert np.all(inside[..., 1] >= 1 - 1e-12) and np.all(inside[..., 2] >= 1 - 1e-12)
    outside = projected_variance(10 * D, 20 * D)
    assert outside[1] < 1


def test_selection_rules():
    assert list(literal_second_plane(np.array([44.9, 45, 90, 135, 135.1]) * D)) == [
        "zx",
        "yz",
        "yz",
        "yz",
        "zx",
    ]
    # Scenario 3 region (theta ~ 30 deg, phi ~ 47 deg): literal says yz, min-variance says zx
    assert literal_second_plane(47 * D) == "yz"
    assert minvar_second_plane(30 * D, 47 * D) == "zx"


def test_sensor_polarity_and_bad_input():
    s = DoaSensor3D("s", (10, 10, 10), polarity=(-1, -1, -1))
    th, _ = s.angles(np.array([2.0, 1.0, 2.0]))
    assert math.degrees(th) == pytest.approx(48.37, abs=0.05)
    with pytest.raises(ConfigError, match="polarity"):
        DoaSensor3D("s", polarity=(1, 0, 1))
    with pytest.raises(MeasurementError, match="finite"):
        check_angles([np.nan, 1.0])
    with pytest.raises(MeasurementError, match="polar"):
        check_angles([0.0, 7.0])
