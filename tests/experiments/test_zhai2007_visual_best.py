"""The best possible beside Zhai 2007's visual experiments (issue 19): the posterior-mean filter
on each family's printed model, the PCRB of the Gaussian cue models, the claims and the section."""

import numpy as np
import pandas as pd
import pytest

from fusetrack.experiments.zhai2007 import visual_best as vb
from fusetrack.experiments.zhai2007.visual import (
    EXPERIMENTS,
    NEW_METHOD,
    best_possible,
    make_tracker,
    pcrb_model,
    run_once,
)
from fusetrack.experiments.zhai2007.visual_scenes import build
from fusetrack.filters import MultipleModelParticleFilter, PriorProposal, ProposalParticleFilter


@pytest.mark.parametrize("exp", ["E9", "E10", "E18-2", "E21"])
def test_posterior_mean_filter_is_a_bootstrap_on_the_printed_model(exp):
    seq = build(EXPERIMENTS[exp][0], np.random.default_rng(3))
    setup = make_tracker(vb.BEST, seq, {"exp": exp, "n_best": 321})
    filt = setup.filt
    assert filt.n_particles == 321
    if NEW_METHOD[exp] in ("MMPF-SP", "multi-cue MMPF"):  # MM-bootstrap: regimes' own motion
        assert isinstance(filt, MultipleModelParticleFilter)
        assert filt.switching.kind == "prior" and setup.prior.mean.shape == (6,)
    else:
        assert isinstance(filt, ProposalParticleFilter)
        assert isinstance(filt.proposal, PriorProposal)  # the bootstrap


def test_pcrb_of_app_b_random_walk_by_hand():
    """E21: x += v + sqrt(5) N(0, 1) with v known, fix of variance 1 per axis, prior ~ 0: per
    axis P_t = (P_{t-1} + 5) / (P_{t-1} + 6), so the bound on the run RMSE over frames 1..T-1
    is sqrt(mean_t 2 P_t); the steady state solves P^2 + 5 P - 5 = 0."""
    motion, sensors, prior = pcrb_model("E21")
    p, ps = 0.0, []
    for _ in range(1, 100):
        p = (p + 5.0) / (p + 6.0)
        ps.append(p)
    assert vb.pcrb_rmse(motion, sensors, 100, prior) == pytest.approx(
        np.sqrt(2 * np.mean(ps)), rel=1e-5
    )
    assert ps[-1] == pytest.approx((-5 + np.sqrt(45)) / 2, rel=1e-9)
    assert pcrb_model("E10") is None  # the edge likelihood has no Gaussian form


def test_best_possible_rows_claims_and_section():
    """E10: the posterior-mean filter lost in 4 of 5 runs and every tracker in 5 of 5, so 'keeps
    lock in every realisation' is impossible; E12: the same posterior-mean filter, but
    condensation keeps lock in every run, so it is possible; E21: lost in 1 of 5, possible."""

    def rows(exp, method, lost, **extra):
        return pd.DataFrame(
            {"exp": exp, "method": method, "run": range(5), "frame": 0, "lost": lost,
             "rmse": 3.0, **extra}
        )  # fmt: skip

    first = pd.concat(
        [
            rows("E10", "MMPF-SP", [1] * 5),
            rows("E10", "condensation", [1] * 5),
            rows("E12", "MMPF-SP", [1] * 5),
            rows("E12", "condensation", [0] * 5),
            rows("E21", "App. B condensation", [0] * 5),
        ]
    )
    lossy = [1, 1, 1, 1, 0]
    best = pd.concat(
        [
            rows("E10", vb.BEST, lossy, n_best=2000),
            rows("E12", vb.BEST, lossy, n_best=2000),
            rows("E21", vb.BEST, [1, 0, 0, 0, 0], n_best=2000),
        ]
    )
    claims, md = best_possible(first, best)
    by_id = {c.id: c for c in claims}
    e10 = by_id["BP_E10_keeps_lock"]
    assert not e10.holds and "impossible" in e10.ours and "(posterior mean)" in e10.statement
    assert (
        by_id["BP_E12_keeps_lock"].holds
        and "(condensation)" in by_id["BP_E12_keeps_lock"].statement
    )
    assert by_id["BP_E12_keeps_lock"].ours.startswith("condensation 0 ")
    assert by_id["BP_E21_keeps_lock"].holds and by_id["BP_E21_keeps_lock"].kind == "diagnostic"
    assert "### The best possible on the printed model" in md
    assert "E10: posterior mean (2000 particles)" in md and "E21: App. B condensation" in md
    assert best_possible(first, best.iloc[:0]) == ([], "")


def test_run_once_runs_the_posterior_mean_filter_alone():
    rows = pd.DataFrame(run_once({"exp": "E21", "best": True, "n_best": 300}, 7))
    assert set(rows["method"]) == {vb.BEST} and len(rows) == 100
    assert rows["rmse"].iloc[0] < 5.0 and not rows["lost"].iloc[0]
