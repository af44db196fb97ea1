"""kushwaha2010-cameras-gap (spec E8/H20 at QVGA): a path that leaves all views but one."""

import numpy as np
import pandas as pd

from fusetrack.experiments.kushwaha2010.camera_gap import (
    gap_trajectory,
    qvga_cameras,
    recovered,
    seen_by,
    windows,
)
from fusetrack.experiments.kushwaha2010.cameras import appearance_model


def test_gap_path_is_seen_by_one_camera_at_the_gap_only():
    cams = qvga_cameras()
    assert cams[0].size == (320, 240) and len(cams) == 10
    target, _ = appearance_model()
    truth = gap_trajectory(cams, target, 22, 9, np.random.default_rng(4))
    n = seen_by(cams, target, truth.positions, truth.quaternions[0])
    assert n.shape == (22,)
    assert list(n[9:11]) == [1, 1] and np.all(np.delete(n, [9, 10]) >= 2)
    steps = np.linalg.norm(np.diff(truth.positions, axis=0), axis=1)
    assert np.all(steps < 0.45)  # one smooth path at 0.4 m/step, no jump at the joins
    assert np.allclose(truth.quaternions, truth.quaternions[0])  # fixed orientation


def test_recovery_test_and_windows():
    assert windows(21) == ((13, 20), (25, 33))
    pre = pd.Series({"T0": 0.1, "T2": 0.1})
    post = pd.Series({"T0": 0.31, "T2": 0.29})  # 2 x 0.1 + 0.1 = 0.3
    assert list(recovered(pre, post)) == [False, True]
