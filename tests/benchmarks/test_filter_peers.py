"""benchmarks/filter_peers.py: the peers compute the variant fusetrack computes (the unscented
proposal density equals Stone Soup's KalmanProposal's), every variant of filters.py is either
timed against a peer or listed with the reason it has none, and a tiny run writes its rows."""

from __future__ import annotations

import json
import sys
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import filter_peers
import filters

pytest.importorskip("stonesoup")


def test_every_variant_has_a_peer_or_a_reason() -> None:
    assert set(filter_peers.PEERS) | set(filter_peers.NO_PEER) == set(filters.OPS)
    assert not set(filter_peers.PEERS) & set(filter_peers.NO_PEER)


def test_point_mass_unscented_proposal_is_stone_soups_kalman_proposal() -> None:
    """For each particle, fusetrack's proposal log-density at its draw equals the density of
    Stone Soup's KalmanPredictor + UnscentedKalmanUpdater posterior of N(x_i, 0)."""
    from scipy.stats import multivariate_normal
    from stonesoup.models.measurement.nonlinear import Cartesian2DToBearing
    from stonesoup.models.transition.linear import LinearGaussianTimeInvariantTransitionModel
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.types.angle import Bearing
    from stonesoup.types.array import StateVector
    from stonesoup.types.detection import Detection
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.state import GaussianState
    from stonesoup.updater.kalman import UnscentedKalmanUpdater

    model = filter_peers.make_model(3)
    rng = np.random.default_rng(0)
    prev = model.prior.mean + rng.normal(0.0, 1.0, (5, 4)) * [1.0, 1.0, 0.3, 0.3]
    z = np.ravel(model.zs[0][0])
    prop = filter_peers.PointMassUnscentedProposal()
    filt = type("F", (), {"motion": model.motion, "sensors": [model.sensor]})()
    state = prop.initialize(model.prior, prev, rng)
    assert not state.any()  # no covariance carried
    x, log_q, _ = prop.draw(state, prev, [z], 1.0, rng, filt)

    cv = LinearGaussianTimeInvariantTransitionModel(model.F, model.Q)
    bearing = Cartesian2DToBearing(4, (0, 1), np.array([[model.sensor.sigma**2]]))
    predictor, updater = KalmanPredictor(cv), UnscentedKalmanUpdater(bearing, alpha=1.0, kappa=-1.0)
    t0 = datetime(2024, 1, 1)
    det = Detection(StateVector([[Bearing(z[0])]]), timestamp=t0 + timedelta(seconds=1),
                    measurement_model=bearing)  # fmt: skip
    for i in range(len(prev)):
        pred = predictor.predict(GaussianState(prev[i], np.zeros((4, 4)), t0), det.timestamp)
        post = updater.update(SingleHypothesis(pred, det))
        m, S = np.ravel(np.asarray(post.state_vector, float)), np.asarray(post.covar, float)
        assert log_q[i] == pytest.approx(multivariate_normal.logpdf(x[i], m, S), abs=1e-4)


def test_a_tiny_run_times_every_library_and_checks_agreement(capsys, tmp_path: Path) -> None:
    pytest.importorskip("particles")  # the bench extra (.ci/run installs dev and docs only)
    out = tmp_path / "filter_peers.json"
    argv = ["--N", "40", "--steps", "2", "--repeats", "2", "--json", "--out", str(out)]
    assert filter_peers.main(argv) == 0
    rows = json.loads(capsys.readouterr().out)
    timed = [r for r in rows if "variant" in r]
    assert [r["variant"] for r in timed] == list(filter_peers.PEERS)
    for r in timed:
        libs = {"fusetrack", *filter_peers.PEERS[r["variant"]][0]}
        assert set(r["cpu_seconds_per_step"]) == libs and set(r["agreement"]) == libs - {
            "fusetrack"
        }
        assert r["ops_per_particle"] == filters.operations(r["variant"], 40)
        for lib in libs - {"fusetrack"}:
            agree = r["agreement"][lib]["agree"]
            assert (r["speedup_over"][lib] is None) == (agree is False)
    tail = json.loads(out.read_text())["results"][-1]
    assert (
        tail["no_peer"] == filter_peers.NO_PEER
        and "stonesoup" in json.loads(out.read_text())["metadata"]["versions"]
    )
