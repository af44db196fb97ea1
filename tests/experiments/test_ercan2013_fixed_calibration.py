"""Fixed per-run camera calibration errors (Ercan et al. 2013 spec §8 item 23) in the simulation."""

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.experiments.ercan2013.scenes import get_scene
from fusetrack.experiments.ercan2013.simulation import (
    camera_readings,
    miscalibrated,
    run_tracking,
    simulate_world,
)


def test_fixed_calibration_moves_the_readings_but_not_what_is_seen():
    scene = get_scene("lab")
    obj, occ = simulate_world(scene, 20, 200, 7)
    white = camera_readings(scene, obj, occ, 7)
    fixed = camera_readings(scene, obj, occ, 7, "fixed")
    assert np.array_equal(np.isnan(white), np.isnan(fixed))  # same steps seen
    real = miscalibrated(scene, 7)
    # the yaw and position errors are drawn once: the same every call, zero-mean per camera set
    assert np.array_equal(real.yaws, miscalibrated(scene, 7).yaws)
    assert not np.array_equal(real.yaws, miscalibrated(scene, 8).yaws)
    dyaw = (real.yaws - scene.cameras.yaws) / scene.cameras.sigma_theta
    dpos = (real.positions - scene.cameras.positions) / scene.cameras.sigma_pos[:, None]
    assert 0.2 < np.std(np.concatenate([dyaw, dpos.ravel()])) < 2.0  # N(0, sigma^2) draws
    # what is left after the miscalibrated cameras' exact image coordinate is white read noise
    resid = fixed - real.image_coordinate(obj[:, None, :])
    seen = ~np.isnan(fixed)
    sd = np.std(resid[seen])
    assert sd == pytest.approx(float(scene.cameras.sigma_read[0]), rel=0.1)
    # and per camera the error against the nominal model has a lasting bias (not white)
    bias = np.nanmean(fixed - scene.cameras.image_coordinate(obj[:, None, :]), axis=0)
    assert np.nanmax(np.abs(bias)) > 3 * sd / np.sqrt(seen.sum(axis=0).max())


def test_unknown_calibration_is_refused():
    with pytest.raises(ConfigError, match="calibration"):
        run_tracking({"scene": "lab", "calibration": "drifting", "steps": 2}, 0)
