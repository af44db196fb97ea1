"""The occlusion-aware likelihood and the waypoint ASIR on short Ercan 2013 runs."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError, ShapeError
from fusetrack.experiments.ercan2013.scenes import square_scene
from fusetrack.experiments.ercan2013.simulation import run_tracking
from fusetrack.sensors.occlusion_aware_camera import OcclusionAwareLikelihood
from fusetrack.world.occlusion import OccluderPriors


def test_likelihood_rejects_impossible_particles_and_never_nan():
    sc = square_scene(True)
    lik = OcclusionAwareLikelihood(sc.cameras, sc.room, 3.33, "gaussian")
    rng = np.random.default_rng(0)
    pri = OccluderPriors(rng.uniform(0, 100, (10, 2)), np.broadcast_to(16 * np.eye(2), (10, 2, 2)))
    x = np.array([[50.0, 50.0], [20.0, 80.0]])  # the first is inside the static occluder
    z = np.array([sc.cameras.image_coordinate(x[1][None, :])[0], np.nan])
    ll = lik.log_likelihood(z, [0, 1], x, pri)
    assert ll[0] == -np.inf and np.isfinite(ll[1])
    all_nan = lik.log_likelihood(np.array([np.nan, np.nan]), [0, 1], x, pri)
    assert not np.isnan(all_nan).any()
    with pytest.raises(ShapeError):
        lik.log_likelihood(np.array([1.0]), [0, 1], x, pri)
    with pytest.raises(ConfigError):
        OcclusionAwareLikelihood(sc.cameras, sc.room, 3.33, "psychic")


QUICK = {"scene": "square-open", "n_occluders": 20, "sigma_psi": 4.0, "k": 4, "method": "fixed",
         "steps": 120, "particles": 500, "burn_in": 20}  # fmt: skip


def test_a_broken_likelihood_fails_the_bound(monkeypatch):
    """The bound below is meaningful: a likelihood that ignores the readings exceeds it."""
    monkeypatch.setattr(
        OcclusionAwareLikelihood,
        "log_likelihood",
        lambda self, z, sel, x, occ=None: np.zeros(len(x)),
    )
    r = run_tracking({**QUICK, "prior": "none"}, 11)[0]
    assert r["rmse_tr"] > 0.25 * r["rmse_max"]


@pytest.mark.parametrize("prior", ["none", "gaussian", "perfect"])
def test_tracker_keeps_rmse_low_on_a_quick_run(prior):
    """4 cameras, 20 occluders, 120 steps: RMSE well below RMSE_max (a broken likelihood loses the object)."""
    r = run_tracking({**QUICK, "prior": prior}, 11)[0]
    assert r["rmse_tr"] < 0.25 * r["rmse_max"]
    assert r["rmse_tr"] < 5.0


def test_selection_runs_and_bad_k():
    r = run_tracking({"scene": "L", "n_occluders": 10, "prior": "gaussian", "sigma_psi": 10.0, "k": 3,
                      "method": "greedy", "model": "perspective", "steps": 12, "particles": 150,
                      "metric_gap": True}, 2)[0]  # fmt: skip
    assert r["greedy_over_brute_mse"] >= 1.0 - 1e-9
    with pytest.raises(ConfigError, match="k="):
        run_tracking({"scene": "L", "k": 13, "method": "greedy", "steps": 2}, 0)
    with pytest.raises(ConfigError, match="config keys"):
        run_tracking({"scene": "L", "colour": "red"}, 0)
