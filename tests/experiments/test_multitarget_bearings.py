"""multitarget-bearings: the quick run's contract files, the triangulation (hand-computed points,
covariance against Monte Carlo), ghost counting and the options (the tracker's birth-only
sensors, which the direct method uses, are tested in tests/tracking/test_birth_only.py)."""

import json

import numpy as np
import pytest

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.experiments.multitarget.scenario import Scene
from fusetrack.experiments.multitarget.triangulation import (
    count_ghosts,
    intersect,
    pair_candidates,
    triangulation_cov,
)
from fusetrack.experiments.registry import validate_options
from fusetrack.filters import GridSpec

NAME = "multitarget-bearings"


def test_quick_run_writes_report_and_claims_with_kinds(tmp_path):
    out = tmp_path / "mt"
    assert main(["run", NAME, "--quick", "--runs", "1", "--out", str(out), "--no-progress"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    report = (out / "report.md").read_text()
    kinds = summary["beyond_the_paper"]["claim_kinds"]
    ids = [c["id"] for c in summary["claims"]]
    assert len(ids) >= 5 and sorted(kinds) == sorted(ids)
    assert set(kinds.values()) <= {"beyond", "diagnostic"} and "beyond" in kinds.values()
    for c in summary["claims"]:
        assert isinstance(c["holds"], bool)
        prefix = "beyond the paper: " if kinds[c["id"]] == "beyond" else "our diagnostic: "
        assert c["statement"].startswith(prefix)
        assert c["id"] in report
    for fig in ("scene_2_arrays.png", "scene_3_arrays.png", "gospa_over_time.png"):
        assert (out / fig).stat().st_size > 0 and fig in report
    assert (out / "results.parquet").exists()


def test_two_perpendicular_bearings_meet_where_drawn():
    # (0, 0) looking at 45 deg and (10, 0) at 135 deg meet at (5, 5), 5 sqrt(2) from each
    p, ra, rb = intersect(np.array([0.0, 0.0]), np.pi / 4, np.array([10.0, 0.0]), 3 * np.pi / 4)
    np.testing.assert_allclose(p, [5.0, 5.0], atol=1e-12)
    np.testing.assert_allclose([ra, rb], [5 * np.sqrt(2)] * 2, rtol=1e-12)
    # the rays are perpendicular, each bearing error moves the point r * dtheta across its ray:
    # Cov = sigma^2 r^2 I = 50 sigma^2 I
    cov = triangulation_cov(p, np.array([0.0, 0.0]), np.array([10.0, 0.0]), 0.01, 0.01)
    np.testing.assert_allclose(cov, 50 * 0.01**2 * np.eye(2), rtol=1e-12, atol=1e-15)


def test_parallel_rays_do_not_meet():
    assert intersect(np.zeros(2), 0.3, np.array([0.0, 1.0]), 0.3) is None


def test_triangulation_covariance_matches_monte_carlo():
    rng = np.random.default_rng(7)
    sa, sb, p = np.array([5.0, 4.0]), np.array([30.0, 16.0]), np.array([12.0, 13.0])
    sigma_a, sigma_b = np.deg2rad(2.0), np.deg2rad(1.0)
    za = np.arctan2(p[1] - sa[1], p[0] - sa[0]) + sigma_a * rng.standard_normal(40_000)
    zb = np.arctan2(p[1] - sb[1], p[0] - sb[0]) + sigma_b * rng.standard_normal(40_000)
    points = np.array([intersect(sa, a, sb, b)[0] for a, b in zip(za, zb)])
    sample = np.cov(points.T)
    cov = triangulation_cov(p, sa, sb, sigma_a, sigma_b)
    # sampling error of a variance at N = 40 000 is ~0.7 %; the linearisation's bias is smaller
    np.testing.assert_allclose(sample, cov, rtol=0.04, atol=0.04 * np.abs(cov).max())
    # unbiased to first order: the second-order bias (~2 cm here) stays well under 5 cm
    assert np.linalg.norm(points.mean(axis=0) - p) < 0.05


def _scene() -> Scene:
    return Scene(GridSpec(), (("A", 0.0, 0.0), ("B", 10.0, 0.0)), 0.01, 0.9, 0.0)


def test_two_targets_give_two_true_points_and_two_ghosts():
    targets = np.array([[3.0, 4.0], [7.0, 4.0]])
    scan = {sid: np.arctan2(targets[:, 1] - y, targets[:, 0] - x) for sid, x, y in _scene().arrays}
    points = np.array([c.point for c in pair_candidates(_scene(), scan, "A", "B")])
    # the ghosts: A's ray to (3, 4) meets B's ray to (7, 4) at (5, 20/3); the other pair at (5, 20/7)
    expected = np.array([[3.0, 4.0], [5.0, 20 / 3], [5.0, 20 / 7], [7.0, 4.0]])
    assert points.shape == (4, 2)
    gaps = np.linalg.norm(points[:, None, :] - expected[None, :, :], axis=-1)
    assert np.all(gaps.min(axis=0) < 1e-9)  # every expected point is there (and only those)
    assert count_ghosts(points, targets, 0.1) == 2
    assert count_ghosts(points, targets[:1], 0.1) == 3
    assert count_ghosts(points, np.empty((0, 2)), 0.1) == 4
    assert count_ghosts(np.empty((0, 2)), targets, 0.1) == 0


def test_rays_that_meet_behind_an_array_give_no_candidate():
    # A looks east, B (east of A) looks east too but slightly north: they meet west of A
    scan = {"A": np.array([0.5]), "B": np.array([0.3])}
    assert pair_candidates(_scene(), scan, "A", "B") == []


@pytest.mark.parametrize("raw", [{"targets": 7}, {"p_detect": 0.0}, {"no_such_key": 1}])
def test_bad_options_are_refused_before_any_work(raw):
    with pytest.raises(ConfigError):
        validate_options(NAME, raw)
