"""angle_pair_information: the PPS plane bearings carry no more information than (theta, phi)."""

import math

import numpy as np
import pytest

from fusetrack.evaluation import angle_pair_information
from fusetrack.sensors import DoaSensor3D

SIGMA = math.sqrt(3.0) * math.pi / 180


def _sensor() -> DoaSensor3D:
    return DoaSensor3D("A0", (0.0, 0.0, 0.0), SIGMA)


def test_xy_plane_alone_is_the_azimuth_information_by_hand():
    # at (1, 0, 0): d theta / dp = (-y, x, 0) / r^2 = (0, 1, 0), so J_xy = diag(0, 1, 0) / sigma^2
    J = angle_pair_information(np.array([1.0, 0.0, 0.0]), _sensor(), ("xy", "zx"))
    np.testing.assert_allclose(J["xy"], np.diag([0.0, 1.0, 0.0]) / SIGMA**2, atol=1e-6 / SIGMA**2)


@pytest.mark.parametrize("planes", [("xy", "yz"), ("xy", "zx")])
@pytest.mark.parametrize("p", [(3.0, 3.0, 1.0), (1.0, 1.0, 3.0), (2.0, 1.0, 2.0)])
def test_joint_planes_equal_3d_single_below_independent_above(p, planes):
    J = angle_pair_information(np.array(p), _sensor(), planes)
    scale = np.linalg.norm(J["3-D"])
    np.testing.assert_allclose(J["pair"], J["3-D"], atol=1e-8 * scale)
    for q in planes:
        assert np.linalg.eigvalsh(J["3-D"] - J[q]).min() >= -1e-9 * scale
    # treating the planes as independent counts shared noise twice: more than the data holds
    assert np.linalg.eigvalsh(J["3-D"] - J["independent"]).min() < -0.05 * scale
