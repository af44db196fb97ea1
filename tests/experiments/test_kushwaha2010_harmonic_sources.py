"""kushwaha2010-harmonic-sources: one scene of each kind runs and scores (the full sweep is the experiment)."""

import numpy as np
import pandas as pd

from fusetrack.experiments.kushwaha2010.harmonic_sources import (
    RANGE_AWARE,
    SENSORS,
    _median_claims,
    run_once,
    separated_pair,
)


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
        "range_aware": True,
    }
    rows = run_once(cfg, 11)
    assert [r["method"] for r in rows] == ["beamform", "EBL", RANGE_AWARE]
    assert all(np.isfinite(r["error"]) and r["error"] >= 0 for r in rows)
    assert rows[0]["n_psd"] == 30 and len(rows[0]["f0_errors"]) == 2


def test_median_claims_pair_runs_and_ignore_one_diverged_run():
    """12 runs; at h = 1.0 one run diverged (8 m): the mean there is above h = 0.4's, but in
    every other run h = 0.4 is worse by 0.1 m, which the median claim shows."""
    rows = []
    for run in range(12):
        for sweep, key, values in (
            ("sources", "n_sources", (1, 2, 3, 4)),
            ("snr", "snr_db", (7.0, 25.0, 52.0)),
            ("separation", "separation", (0.2, 1.0, 5.0)),
            ("directivity", "directivity", (0.0, 1.0, 3.0)),
            ("n_psd", "n_psd", (10, 30)),
        ):
            for v in values:
                rows.append(
                    {"sweep": sweep, key: v, "run": run, "method": "beamform", "error": 0.5}
                )
        rows.append(
            {"sweep": "directivity", "directivity": 1.0, "run": run, "method": "EBL", "error": 1.0}
        )
        for h, err in ((0.4, 0.6), (1.0, 8.0 if run == 0 else 0.5)):
            rows.append(
                {
                    "sweep": "harmonicity",
                    "harmonicity": h,
                    "run": run,
                    "method": "beamform",
                    "error": err,
                }
            )
    df = pd.DataFrame(rows)
    assert df[df.harmonicity == 1.0].error.mean() > df[df.harmonicity == 0.4].error.mean()
    claims = {c.id: c for c in _median_claims(df, 1.0)}
    assert claims["graceful_with_harmonicity_median"].holds
    assert claims["beamform_more_robust_than_ebl_median"].holds
    assert not claims["error_falls_with_snr_median"].holds  # no difference: nothing shown
