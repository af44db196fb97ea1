"""lee2009-rfid-camera's best possible: the two cameras' Fisher information, attained by the
exact two-ray inversion (Eq. 5.40) where the rays cross well, and the rows beside the tables."""

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.experiments.lee2009 import rfid_camera as rc
from fusetrack.sensors import WallCameraPair

CAMS = WallCameraPair(rc.ROOM, f=800.0, pixel_sigma=1.0)


def test_jacobian_matches_finite_differences():
    p = np.array([6.3, 2.7])
    eps = 1e-6
    num = np.column_stack(
        [(CAMS.image(p + eps * e) - CAMS.image(p - eps * e)) / (2 * eps) for e in np.eye(2)]
    )
    np.testing.assert_allclose(CAMS.jacobian(p), num, rtol=1e-7)


def test_fisher_information_by_hand():
    """(5, 4) is on both cameras' axes: camera 1 at (0, 4), depth 5: du1/dx = 0, du1/dy = f / 5;
    camera 2 at (5, 0), depth 4: du2/dx = f / 4, du2/dy = 0. F = H^T H / 1 px^2."""
    F = CAMS.fisher_information(np.array([5.0, 4.0]))
    np.testing.assert_allclose(F, np.diag([(800 / 4) ** 2, (800 / 5) ** 2]))
    with pytest.raises(ConfigError, match="pixel_sigma"):
        WallCameraPair(rc.ROOM, pixel_sigma=0.0).fisher_information(np.array([5.0, 4.0]))


def test_exact_inversion_attains_the_bound():
    """Eq. 5.40's mean square error at a well-conditioned point equals the CRLB's trace
    (4,000 draws: the estimate's s.e. is ~2 %)."""
    p = np.array([6.0, 2.5])
    rng = np.random.default_rng(7)
    err = [np.sum((CAMS.refine(p, CAMS.image(p, rng)) - p) ** 2) for _ in range(4000)]
    bound = np.trace(np.linalg.inv(CAMS.fisher_information(p)))
    assert np.mean(err) == pytest.approx(bound, rel=0.08)


def test_best_rows_skip_nearly_parallel_rays():
    """A point on the line through the cameras (5 y + 4 x = 20) has no bound row; the room
    centre's error is kept for every point."""
    pts = np.array([[6.0, 2.5], [2.5, 2.0]])
    assert rc.crossing_deg(CAMS, pts)[1] == pytest.approx(0.0, abs=1e-6)
    sq = rc.best_possible_sq(CAMS, pts, [0.1, 0.2])
    assert len(sq[rc.CRLB]) == 1 and sq[rc.EQ540_CROSSING] == [0.1]
    assert sq[rc.TRIVIAL] == pytest.approx([1.0 + 2.25, 6.25 + 4.0])
