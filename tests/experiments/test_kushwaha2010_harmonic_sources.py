"""kushwaha2010-harmonic-sources: one scene of each kind runs and scores (the full sweep is the experiment)."""

import numpy as np

from fusetrack.experiments.kushwaha2010.harmonic_sources import SENSORS, run_once, separated_pair


def test_separated_pair_geometry():
    rng = np.random.default_rng(0)
    for d in (0.1, 2.0, 8.0):
        p = separated_pair(d, rng)
        assert abs(np.hypot(*(p[0] - p[1])) - d) < 1e-9
        assert np.all((p >= 0.5) & (p <= [9.5, 4.5]))
        assert np.min(np.hypot(*(p[:, None] - SENSORS[None]).transpose(2, 0, 1))) >= 1.0


def test_one_directivity_scene_scores_beamform_and_ebl():
    cfg = {
        "gibbs_samples": 5,
        "snr_db": 25.0,
        "sweep": "directivity",
        "n_sources": 2,
        "directivity": 0.0,
        "ebl": True,
    }
    rows = run_once(cfg, 11)
    assert [r["method"] for r in rows] == ["beamform", "EBL"]
    assert all(np.isfinite(r["error"]) and r["error"] >= 0 for r in rows)
    assert rows[0]["n_psd"] == 30 and len(rows[0]["f0_errors"]) == 2
