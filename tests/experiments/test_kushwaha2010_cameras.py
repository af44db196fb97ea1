"""kushwaha2010-cameras-a/-b: one tiny run and the one-camera gap (Kushwaha 2010, Ch. V)."""

import numpy as np
import pandas as pd

from fusetrack.experiments.kushwaha2010.cameras import (
    ABLATIONS,
    GAP_START,
    SETUPS,
    TRACKERS,
    appearance_model,
    gap_mask,
    run_once,
)
from fusetrack.world.ellipsoid_scene import render_frames, smooth_trajectory


def test_tiny_run_has_every_tracker_and_t0_bytes():
    cfg = {
        "setup": "a",
        "steps": 3,
        "n_particles": 50,
        "n_particles_2d": 30,
        "gap": 0,
        "rotating": True,
    }
    df = pd.DataFrame(run_once(cfg, 7))
    assert set(df.tracker) == {*TRACKERS, *ABLATIONS, "T4-eq103"}
    assert np.all(np.isfinite(df.err3d)) and np.all(df.t.isin([1, 2]))
    t0 = df[df.tracker == "T0"]
    assert np.all(t0["bytes"] == 80 + 8 * 50 * t0.cameras_used)


def test_gap_leaves_exactly_one_camera():
    setup = SETUPS["b"]
    target, _ = appearance_model()
    cams = setup.cameras()
    rng = np.random.default_rng(3)
    truth = smooth_trajectory(rng, GAP_START + 3, setup.low, setup.high, speed=setup.speed)
    hidden = gap_mask(
        cams, target, truth.positions, truth.quaternions, range(GAP_START, GAP_START + 2)
    )
    assert hidden[:GAP_START].sum() == 0
    frames = render_frames(cams, target, truth, rng, hidden=hidden)
    assert frames.participating[GAP_START].sum() == 1
    assert frames.participating[GAP_START + 1].sum() == 1
    assert frames.participating[GAP_START - 1].sum() >= 2
