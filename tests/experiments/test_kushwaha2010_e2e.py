"""End to end: every Kushwaha 2010 experiment runs through the CLI and writes the contract files."""

import json

import pandas as pd
import pytest

from fusetrack.cli import main

EXPECTED = {
    "kushwaha2010-sbe": {
        "av_beats_each_modality",
        "product_less_uncertain",
        "centralized_beats_hybrid",
        "two_audio_fix_false_video_peaks",
        "product_more_fragile",
        "packet_loss_degrades_gracefully",
        "BP_sbe_above_bound",
        "BP_average_2m_possible",
    },
    "kushwaha2010-mcmcda": {
        "product_lower_error",
        "sum_higher_success",
        "av_lowest_error",
        "av_reduces_error",
        "mcmcda_beats_sbe",
        "BP_mcmcda_above_bound",
        "BP_sbe_above_bound",
        "BP_table8_AV_possible",
    },
    "kushwaha2010-crossing": {
        "three_tracks",
        "per_track_errors",
        "audio_merges_at_crossing",
        "BP_crossing_above_bound",
        "BP_fig26_track_1_possible",
    },
    "kushwaha2010-beamformer": {
        "min_error_mid_range",
        "error_grows_far",
        "error_grows_near",
        "BP_nearest_beam_mid_range",
    },
    "kushwaha2010-timesync": {
        "residual_far_below_period",
        "offset_hurts_tracking",
        "small_offset_harmless",
        "BP_sync_not_below_crlb",
        "BP_sync_attains_crlb",
        "BP_tracking_above_pcrb",
    },
}
# Reports that show the best possible beside their error tables (issue 19): the heading and
# the bound's column.
BEST_POSSIBLE = {
    "kushwaha2010-sbe": ("## The best possible: PCRB", "PCRB mean-error bound (m)"),
    "kushwaha2010-mcmcda": ("## The best possible: PCRB", "PCRB mean-error bound (m)"),
    "kushwaha2010-crossing": ("## The best possible: PCRB", "PCRB mean-error bound (m)"),
    "kushwaha2010-timesync": ("CRLB RMS, RBS window (µs)", "PCRB of the synchronised bearings"),
}


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_experiment_quick(tmp_path, name):
    out = tmp_path / name
    assert main(["run", name, "--quick", "--runs", "1", "--out", str(out), "--no-progress"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["experiment"] == name
    claims = {c["id"]: c for c in summary["claims"]}
    assert EXPECTED[name] <= set(claims)
    for c in claims.values():
        assert isinstance(c["holds"], bool) and c["paper"] is not None and "ours" in c
    df = pd.read_parquet(out / "results.parquet")
    assert len(df) > 0 and "run" in df.columns
    report = (out / "report.md").read_text()
    assert "Differences from the paper" in report
    for text in BEST_POSSIBLE.get(name, ()):
        assert text in report
    for line in report.splitlines():
        if line.startswith("![") and "](" in line:
            assert (out / line.split("](")[1].rstrip(")")).exists()
