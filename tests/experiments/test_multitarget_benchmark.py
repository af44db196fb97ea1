"""multitarget-benchmark: the quick run's contract files, the scenario generator's statistics
(births, clutter, P_D) on a fixed seed, the crossing geometry, the PHD's prior, the paired
statistics of the claims and the options."""

import json

import numpy as np
import pandas as pd
import pytest

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.experiments.multitarget.benchmark_claims import paired_difference
from fusetrack.experiments.multitarget.benchmark_scenario import (
    HALF,
    RADAR_BOX,
    Setting,
    scenario_stats,
    simulate_births_and_deaths,
    simulate_crossing,
    simulate_scans,
)
from fusetrack.experiments.multitarget.benchmark_scoring import count_bias
from fusetrack.experiments.multitarget.benchmark_trackers import phd_prior, phd_tracker
from fusetrack.experiments.registry import validate_options

NAME = "multitarget-benchmark"
FIGURES = ("gospa_over_time.png", "cardinality_over_time.png", "tracks_sparse.png")


def test_quick_run_writes_report_claims_and_figures(tmp_path):
    out = tmp_path / "mtb"
    assert main(["run", NAME, "--quick", "--runs", "1", "--out", str(out), "--no-progress"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    report = (out / "report.md").read_text()
    kinds = summary["beyond_the_paper"]["claim_kinds"]
    ids = [c["id"] for c in summary["claims"]]
    assert {
        "jpda_not_worse_than_gnn_dense",
        "mht_not_worse_than_jpda_crossing",
        "phd_cardinality_unbiased",
        "scenario_statistics",
        "BP_trackers_above_floor",
        "BP_clairvoyant_attains_floor",
    } <= set(ids)
    assert kinds["BP_trackers_above_floor"] == kinds["BP_clairvoyant_attains_floor"] == "diagnostic"
    assert "## Best possible" in report and "oracle floor, whole run" in report
    assert sorted(kinds) == sorted(ids) and set(kinds.values()) == {"beyond", "diagnostic"}
    for c in summary["claims"]:
        assert isinstance(c["holds"], bool) and c["id"] in report
    for fig in FIGURES:
        assert (out / fig).stat().st_size > 0 and fig in report
    df = pd.read_parquet(out / "results.parquet")
    assert set(df.tracker) == {"GNN", "JPDA", "MHT", "MCMCDA", "GM-PHD", "PMB"}
    assert set(df.scenario) == {"sparse", "dense", "crossing"}
    for col in ("gospa", "ospa2", "mota", "motp", "id_switches", "fragmentations", "floor_online"):
        assert col in df.columns


def test_births_clutter_and_detections_follow_their_models():
    setting = Setting(p_detect=0.9, clutter=5.0, p_survive=0.98, birth_rate=0.5)
    scans = 400
    world = simulate_births_and_deaths(setting, scans, np.random.default_rng(3))
    reports = simulate_scans(world, setting, np.random.default_rng(4))
    stats = scenario_stats(world, reports)
    # births after scan 0: Poisson(0.5 * 399); within 3 sd
    expected = 0.5 * (scans - 1)
    assert abs(stats["births"] - expected) <= 3 * np.sqrt(expected)
    # clutter per sensor per scan: the mean of 800 Poisson(5) draws, sd sqrt(5 / 800)
    assert abs(stats["clutter_per_scan"] - 5.0) <= 3 * np.sqrt(5.0 / (2 * scans))
    # detections: binomial with p = 0.9 over every (present target, scan, sensor)
    n = 2 * world.counts.sum()
    assert n > 5000
    assert abs(stats["detected_fraction"] - 0.9) <= 3 * np.sqrt(0.9 * 0.1 / n)
    # a target, once dead, never comes back: present on one contiguous run of scans
    on = np.all(np.isfinite(world.states[..., :2]), axis=2)
    for i in range(on.shape[1]):
        k = np.flatnonzero(on[:, i])
        assert k[0] == world.born[i] and k[-1] == world.last[i] and k.size == k[-1] - k[0] + 1
    # clutter lies in the sensor's clutter region
    clutter = [m for m, o in zip(reports.measurements, reports.origins) if o < 0]
    pos = np.array([m.value for m in clutter if m.sensor_id == "pos"])
    radar = np.array([m.value for m in clutter if m.sensor_id == "radar"])
    assert np.all(np.abs(pos) <= HALF)
    r0, r1, b0, b1 = RADAR_BOX
    assert np.all((radar[:, 0] >= r0) & (radar[:, 0] <= r1))
    assert np.all((radar[:, 1] >= b0) & (radar[:, 1] <= b1))


def test_steady_state_start_and_survival():
    # 200 runs of 2 scans: the first scan's count is Poisson(rate / (1 - P_S)) = Poisson(5)
    setting = Setting(birth_rate=0.1, p_survive=0.98)
    first = [
        simulate_births_and_deaths(setting, 2, np.random.default_rng(s)).counts[0]
        for s in range(200)
    ]
    assert abs(np.mean(first) - 5.0) <= 3 * np.sqrt(5.0 / 200)


def test_crossing_pairs_meet_at_mid_run_at_the_set_angle():
    world = simulate_crossing(pairs=4, scans=21, half_angle_deg=10.0)
    mid = 10  # t = 10 s is mid-run for 21 scans
    p = world.states[:, :, :2]
    for j in range(4):
        a, b = p[:, 2 * j], p[:, 2 * j + 1]
        np.testing.assert_allclose(a[mid], b[mid], atol=1e-9)
        va, vb = world.states[0, 2 * j, 2:], world.states[0, 2 * j + 1, 2:]
        cos = va @ vb / (np.linalg.norm(va) * np.linalg.norm(vb))
        np.testing.assert_allclose(np.degrees(np.arccos(cos)), 20.0, rtol=1e-9)
        # they start in their entry region, 400 m out, within 30 m of its centre line
        assert abs(np.linalg.norm(a[0]) - 400.0) < 30.0
    assert world.counts.tolist() == [8] * 21


def test_phd_prior_is_the_steady_state_after_the_first_prediction():
    setting = Setting(birth_rate=0.1, p_survive=0.98)
    phd = phd_tracker(setting).filter
    predicted = phd.predict(phd_prior(setting), 0.0)
    # survivors 0.98 * 5 plus births 0.1: the steady state 5 again
    assert predicted.expected_count == pytest.approx(5.0, rel=1e-12)


def test_paired_difference_and_count_bias_by_hand():
    df = pd.DataFrame(
        {
            "scenario": ["dense"] * 4,
            "tracker": ["A", "B", "A", "B"],
            "run": [0, 0, 1, 1],
            "gospa": [3.0, 1.0, 5.0, 2.0],
        }
    )
    mean, se = paired_difference(df, "dense", "A", "B", "gospa")
    # differences 2 and 3: mean 2.5, sd 0.7071, SE 0.5
    assert mean == pytest.approx(2.5) and se == pytest.approx(0.5)
    assert count_bias([0.0, 9.0, 3.0, 5.0], [1, 1, 2, 4], settle=2) == pytest.approx(1.0)


def test_options_are_validated():
    opts = validate_options(NAME, {"dense_clutter": "20"})
    assert opts.dense_clutter == 20.0  # type: ignore[attr-defined]
    with pytest.raises(ConfigError, match="scans"):
        validate_options(NAME, {"scans": "3"})
    with pytest.raises(ConfigError, match="not a known key"):
        validate_options(NAME, {"clutter": "3"})
