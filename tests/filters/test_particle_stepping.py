"""The proposal-based particle filters as stepping filters over frozen beliefs: the step with
the transition prior is predict + update draw for draw, the beliefs carry everything (a filter
can serve interleaved runs), measurements name sensors, and the update reports log p(z_k|z_1:k-1)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fusetrack.core import (
    Gaussian,
    LikelihoodFilter,
    Measurement,
    MeasurementError,
    SteppingFilter,
    UnknownSensorError,
)
from fusetrack.filters import (
    KalmanFilter,
    MultipleModelParticleFilter,
    ProposalParticleFilter,
    SPPEKFProposal,
    run_filter,
)
from fusetrack.filters.cpf_sp import CPFSPProposal
from fusetrack.filters.mcmc_moves import RandomWalkMove
from fusetrack.motion import ConstantVelocity, LinearGaussianMotion
from fusetrack.sensors import Bearing, LinearGaussianSensor, PositionFix

CV = ConstantVelocity(ndim=1, q=0.3)
FIX = PositionFix("p", cov=[[0.5]], position_index=(0,))
PRIOR = Gaussian(np.array([0.0, 1.0]), np.diag([2.0, 0.5]))


def _zs(steps: int = 6) -> list[list[Measurement]]:
    return [[Measurement(k + 1.0, "p", [1.1 * (k + 1) - 0.3 * (k % 2)])] for k in range(steps)]


@pytest.mark.parametrize("move", [None, RandomWalkMove(0.2)])
def test_bootstrap_step_is_predict_then_update(move):
    pf = ProposalParticleFilter(CV, [FIX], n_particles=300, move=move)
    assert isinstance(pf, SteppingFilter) and isinstance(pf, LikelihoodFilter)
    r1, r2 = np.random.default_rng(3), np.random.default_rng(3)
    a, b = pf.initialize(PRIOR, r1), pf.initialize(PRIOR, r2)
    for ms in _zs():
        a = pf.step(a, 1.0, ms, r1)
        b = pf.update(pf.predict(b, 1.0, r2), ms, r2)
    np.testing.assert_array_equal(a.states, b.states)
    np.testing.assert_array_equal(a.mean, b.mean)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.states = b.states  # type: ignore[misc]


def test_multiple_model_step_is_predict_then_update():
    models = [ConstantVelocity(ndim=1, q=0.01), ConstantVelocity(ndim=1, q=1.0)]
    mm = MultipleModelParticleFilter(models, [[0.9, 0.1], [0.2, 0.8]], [FIX], 300)
    assert isinstance(mm, SteppingFilter) and isinstance(mm, LikelihoodFilter)
    r1, r2 = np.random.default_rng(4), np.random.default_rng(4)
    a, b = mm.initialize(PRIOR, r1), mm.initialize(PRIOR, r2)
    for ms in _zs():
        a = mm.step(a, 1.0, ms, r1)
        b = mm.update(mm.predict(b, 1.0, r2), ms, r2)
    np.testing.assert_array_equal(a.states, b.states)
    np.testing.assert_array_equal(a.proposal.modes, b.proposal.modes)
    np.testing.assert_array_equal(a.proposal.model_probs, b.proposal.model_probs)


def test_interleaved_runs_equal_separate_runs():
    """Everything a run carries is in its belief (the EKF bank too): one filter object can
    advance two runs with different priors in turn and each equals its run alone."""
    pf = ProposalParticleFilter(CV, [FIX], SPPEKFProposal(n_channels=5), n_particles=100)
    other = Gaussian(np.array([3.0, -1.0]), np.diag([1.0, 0.2]))

    def alone(prior, seed):
        rng = np.random.default_rng(seed)
        b = pf.initialize(prior, rng)
        for ms in _zs():
            b = pf.step(b, 1.0, ms, rng)
        return b.mean

    ra, rb = np.random.default_rng(1), np.random.default_rng(2)
    a, b = pf.initialize(PRIOR, ra), pf.initialize(other, rb)
    for ms in _zs():
        a, b = pf.step(a, 1.0, ms, ra), pf.step(b, 1.0, ms, rb)
    np.testing.assert_array_equal(a.mean, alone(PRIOR, 1))
    np.testing.assert_array_equal(b.mean, alone(other, 2))


def test_measurements_must_name_the_sensors():
    pf = ProposalParticleFilter(CV, [FIX], n_particles=50)
    rng = np.random.default_rng(0)
    b = pf.initialize(PRIOR, rng)
    with pytest.raises(UnknownSensorError, match="'q'"):
        pf.step(b, 1.0, [Measurement(1.0, "q", [0.0])], rng)
    with pytest.raises(MeasurementError, match="one per sensor"):
        pf.step(b, 1.0, [Measurement(1.0, "p", [0.0]), Measurement(1.0, "p", [0.1])], rng)
    skipped = pf.step(b, 1.0, [Measurement(1.0, "p", [np.nan])], rng)  # counted, not used
    assert pf.stats.skipped_measurements == 1 and np.all(np.isfinite(skipped.mean))


def test_cpf_sp_reads_its_sensor_weights_as_a_side_input():
    """The weights W_k arrive as a measurement of "sensor-weights": W = (1, 0) and (2, 0) give
    the same step (they are normalised), equal weights (none given) another one; a filter whose
    proposal reads no side input refuses the id."""
    sensors = [Bearing("a", [0.0, 0.0], 0.05), Bearing("b", [40.0, 0.0], 0.05)]
    motion = ConstantVelocity(q=0.05)
    prior = Gaussian(np.array([10.0, 20.0, 1.0, 0.0]), np.diag([4.0, 4.0, 0.1, 0.1]))
    pf = ProposalParticleFilter(motion, sensors, CPFSPProposal(4), 100)
    assert pf.proposal.side_inputs == ("sensor-weights",)
    truth = np.array([11.0, 20.0, 1.0, 0.0])
    zs = [Measurement(1.0, s.sensor_id, s.predict(truth)) for s in sensors]

    def step(weights):
        rng = np.random.default_rng(5)
        side = [] if weights is None else [Measurement(1.0, "sensor-weights", weights)]
        return pf.step(pf.initialize(prior, rng), 1.0, [*zs, *side], rng).mean

    np.testing.assert_array_equal(step([1.0, 0.0]), step([2.0, 0.0]))
    assert not np.array_equal(step([1.0, 0.0]), step(None))
    bootstrap = ProposalParticleFilter(motion, sensors, n_particles=10)
    rng = np.random.default_rng(0)
    with pytest.raises(UnknownSensorError, match="sensor-weights"):
        bootstrap.step(
            bootstrap.initialize(prior, rng),
            1.0,
            [zs[0], Measurement(1.0, "sensor-weights", [1.0, 0.0])],
            rng,
        )


def test_log_likelihood_of_the_sis_filter_matches_the_kalman_filter():
    F = np.array([[1.0, 1.0], [0.0, 1.0]])
    motion = LinearGaussianMotion(F=F, Q=0.3 * np.array([[1 / 3, 1 / 2], [1 / 2, 1.0]]))
    sensor = LinearGaussianSensor("p", H=[[1.0, 0.0]], R=[[0.5]])
    zs = [m for ms in _zs(10) for m in ms]
    exact = run_filter(KalmanFilter(motion, [sensor]), PRIOR, zs, t0=0.0, log_likelihood=True)
    for filt in (
        ProposalParticleFilter(motion, [sensor], n_particles=20_000),
        MultipleModelParticleFilter([motion], [[1.0]], [sensor], 20_000),
    ):
        track = run_filter(
            filt, PRIOR, zs, rng=np.random.default_rng(6), t0=0.0, log_likelihood=True
        )
        assert float(track.info["log_likelihood"]) == pytest.approx(
            float(exact.info["log_likelihood"]), abs=0.1
        )


class _Nowhere:
    """A sensor under which no state can have produced the report (log-likelihood -inf)."""

    sensor_id, dim = "n", 1

    def log_likelihood(self, z, x):
        return np.full(x.shape[:-1], -np.inf)


def test_vanished_weights_are_counted_and_warned_once():
    from fusetrack.core import DegenerateWeightsWarning

    pf = ProposalParticleFilter(CV, [FIX, _Nowhere()], n_particles=50)
    rng = np.random.default_rng(0)
    b = pf.initialize(PRIOR, rng)
    with pytest.warns(DegenerateWeightsWarning, match="ProposalParticleFilter") as caught:
        for k in range(3):
            b = pf.step(b, 1.0, [Measurement(k + 1.0, "n", [0.0])], rng)
    assert len(caught) == 1 and pf.stats.degenerate_steps == 3
    assert np.all(np.isfinite(b.mean))  # equal weights kept, never NaN
