"""kushwaha2010-harmonic-sources' best possible: the localiser-model CRLB, its centroid, the
field centre, and the report rows and claims built from them."""

import numpy as np
import pandas as pd
import pytest

from fusetrack.experiments.kushwaha2010.harmonic_bound import (
    best_possible_claims,
    best_possible_text,
    centroid_bound,
    field_prior_information,
    localiser_bound,
    scene_bound,
)
from fusetrack.experiments.kushwaha2010.harmonic_sources import (
    CLAIM_KINDS,
    FIELD,
    _sweep_table,
    _sweep_views,
    _with_best,
    network,
)
from fusetrack.world import HarmonicSource


def test_centroid_and_prior_by_hand():
    C = np.diag([1.0, 2.0, 3.0, 4.0])  # two sources
    assert np.allclose(centroid_bound(C), np.diag([1.0, 1.5]))
    assert np.allclose(field_prior_information(FIELD, 1), np.diag([12 / 100, 12 / 25]))


def _source(xy):
    return HarmonicSource(np.array(xy), 80.0, 1.0 / np.arange(1, 13))


def test_localiser_bound_scales_with_the_assumed_noise():
    """Far from the prior's reach the CRLB scales as rel_sigma²; it is symmetric positive."""
    net = network()
    src = [_source([3.0, 2.0])]
    C1 = localiser_bound(net, src, 0.01, FIELD)
    C2 = localiser_bound(net, src, 0.02, FIELD)
    assert np.allclose(C1, C1.T) and np.all(np.linalg.eigvalsh(C1) > 0)
    assert np.trace(C2) / np.trace(C1) == pytest.approx(4.0, rel=0.02)


def test_close_pair_is_bounded_by_the_prior_and_the_field_centre_is_exact():
    net = network()
    b = scene_bound(
        net,
        [_source([4.0, 2.5]), _source([6.0, 2.5])],
        0.01,
        rel_sigma=0.05,
        field_box=FIELD,
        seconds=1.0,
    )
    assert b.centre_error == pytest.approx(1.0)  # both sources 1 m from (5, 2.5)
    assert 0 < b.mean < b.rms < 3.0 and 0 < b.f0_rms < 1e-3


def _rows(error_one: float) -> pd.DataFrame:
    rows = []
    for m, err in ((1, error_one), (2, 3.0), (3, 2.0), (4, 1.0)):
        rows.append(
            {
                "sweep": "sources",
                "method": "beamform",
                "n_sources": m,
                "error": err,
                "bound_mean": 0.1,
                "centre_error": 2.5,
                "f0_bound_rms": 1e-5,
            }
        )
    return pd.DataFrame(rows)


def test_report_table_shows_the_best_possible():
    df = _rows(0.5)
    by_m = df.groupby("n_sources")["error"].mean()
    s = pd.Series([1.0], index=[25.0])
    view = _sweep_views(by_m, None, s, s, s, s, s, s)[0]
    table = _sweep_table(_with_best(view, df, "sources", "n_sources"))
    assert "best possible: CRLB of the localiser's model (m) | 0.100 |" in table
    assert "trivial: field centre (m) | 2.500 |" in table
    assert "| sources | 1.625 | 0.100 |" in best_possible_text(df, 0.001)


def test_claims_fail_below_the_bound_and_above_the_field_centre():
    ok = {
        c.id: c.holds for c in best_possible_claims(CLAIM_KINDS, _rows(0.5), np.zeros(0), _by(0.5))
    }
    assert ok["BP_localiser_above_crlb"] and ok["BP_beats_field_centre_one_source"]
    assert not ok["BP_beats_field_centre_two_sources"]  # 3.0 m against 2.5 m
    assert ok["BP_f0_spread_possible"]  # 0.01 Hz against a 1e-5 Hz bound
    low = best_possible_claims(CLAIM_KINDS, _rows(0.01), np.zeros(0), _by(0.01))
    assert not {c.id: c.holds for c in low}["BP_localiser_above_crlb"]


def _by(error_one: float) -> pd.Series:
    return _rows(error_one).groupby("n_sources")["error"].mean()
