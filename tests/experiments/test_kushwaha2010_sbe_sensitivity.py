"""kushwaha2010-sbe: the engine-offset and band re-runs are paired with base run by run."""

import numpy as np
import pandas as pd

from fusetrack.experiments.kushwaha2010.sbe import (
    _sensitivity_claims,
    _sensitivity_table,
    scene_config,
)
from fusetrack.experiments.kushwaha2010.scene import VARIANTS


def test_sensitivity_conditions_change_one_choice():
    assert scene_config("engine_at_centre", 0.0).engine_offset == 0.0
    assert scene_config("band_300hz", 0.0).filter_band == (300.0, 4000.0)
    base = scene_config("base", 0.0)
    assert base.engine_offset == 1.5 and base.filter_band == (100.0, 4000.0)


def test_sensitivity_claims_pair_runs():
    rng = np.random.default_rng(0)
    rows = []
    for run in range(10):
        common = rng.normal(0, 2.0)  # pass-to-pass spread far above the effects
        for cond, shift in (("base", 1.0), ("engine_at_centre", 0.0), ("band_300hz", 1.0)):
            for v in VARIANTS:
                err = 5.0 + common + (shift if v.startswith("A") and "V" not in v else 0.0)
                err += {"VS": 0.5, "VP": 0.5, "AVCS": -1.0}.get(v, 0.0)
                for loss in (0.0, 0.02):
                    rows.append(
                        {
                            "run": run,
                            "condition": cond,
                            "variant": v,
                            "sensors": "all",
                            "packet_loss": loss,
                            "error": err + rng.normal(0, 0.01),
                        }
                    )
    claims = {c.id: c for c in _sensitivity_claims(_sensitivity_table(pd.DataFrame(rows)))}
    assert claims["centred_engine_lowers_audio_error"].holds  # paired: 1 m against 2 m spread
    assert claims["centred_engine_audio_beats_video"].holds  # A 5.0 < V 5.5 at the centre
    assert not claims["band_300hz_lowers_audio_error"].holds  # no change with the band
    assert not claims["band_300hz_audio_beats_video"].holds  # A 6.0 > V 5.5
    assert claims["centred_engine_av_sum_beats_each"].holds
