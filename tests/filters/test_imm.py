"""IMM filter: the mixing step by hand, one model = its Kalman filter, identical models = the
Markov chain, batches = separate runs, and a manoeuvre shifts the probability to the turn model."""

import numpy as np
import pytest

from fusetrack.core import ConfigError, Gaussian, Measurement, filter_step
from fusetrack.filters import KalmanFilter
from fusetrack.filters.imm import IMMBelief, InteractingMultipleModel, imm_mix
from fusetrack.motion import ConstantVelocity, CoordinatedTurn, RandomWalk
from fusetrack.sensors import PositionFix


def test_mixing_step_by_hand() -> None:
    # two 1-D models: mu = (0.6, 0.4), x = (0, 1), P = (1, 2), p = [[0.9, 0.1], [0.2, 0.8]]
    means = np.array([[0.0], [1.0]])
    covs = np.array([[[1.0]], [[2.0]]])
    x0, p0, c = imm_mix(means, covs, np.array([0.6, 0.4]), np.array([[0.9, 0.1], [0.2, 0.8]]))
    # c1 = 0.54 + 0.08 = 0.62, c2 = 0.06 + 0.32 = 0.38
    np.testing.assert_allclose(c, [0.62, 0.38], atol=1e-15)
    # model 1: mu_{1|1} = 0.54/0.62, mu_{2|1} = 0.08/0.62; x0 = 0.08/0.62
    a, b = 0.54 / 0.62, 0.08 / 0.62
    xa = b
    pa = a * (1.0 + xa**2) + b * (2.0 + (1.0 - xa) ** 2)
    # model 2: mu_{1|2} = 0.06/0.38, mu_{2|2} = 0.32/0.38
    e, f = 0.06 / 0.38, 0.32 / 0.38
    xb = f
    pb = e * (1.0 + xb**2) + f * (2.0 + (1.0 - xb) ** 2)
    np.testing.assert_allclose(x0[:, 0], [xa, xb], rtol=1e-14)
    np.testing.assert_allclose(p0[:, 0, 0], [pa, pb], rtol=1e-14)
    assert xa == pytest.approx(0.12903225806451613)


def test_unreachable_model_keeps_its_estimate() -> None:
    x0, _, c = imm_mix(
        np.array([[0.0], [5.0]]), np.ones((2, 1, 1)), np.array([1.0, 0.0]), np.eye(2)
    )
    assert c.tolist() == [1.0, 0.0]
    assert x0[:, 0].tolist() == [0.0, 5.0]


def _track(seed: int, n: int = 15) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    x, out = np.array([0.0, 0.0, 1.0, 0.5]), []
    cv = ConstantVelocity(q=0.1)
    for _ in range(n):
        x = cv.sample(x, 1.0, rng)
        out.append(x[:2] + rng.standard_normal(2) * 0.5)
    return out


def test_one_model_equals_kalman_filter() -> None:
    sensor = PositionFix("p", cov=0.25 * np.eye(2))
    cv = ConstantVelocity(q=0.1)
    imm = InteractingMultipleModel([cv], [[1.0]], [sensor], filter_cls=KalmanFilter)
    kf = KalmanFilter(cv, [sensor])
    prior = Gaussian(np.zeros(4), 4.0 * np.eye(4))
    b, g = imm.initialize(prior), prior
    for k, z in enumerate(_track(1)):
        m = [Measurement(float(k), "p", z)]
        b = imm.update(imm.predict(b, 1.0), m)
        g = kf.update(kf.predict(g, 1.0), m)
        out = b.combined()
        np.testing.assert_allclose(out.mean, g.mean, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(out.cov, g.cov, rtol=1e-12, atol=1e-12)
        assert b.probs.tolist() == [1.0]


def test_identical_models_follow_the_markov_chain() -> None:
    # equal likelihoods: mu_t = mu_{t-1} P, and the estimate is the single KF's
    sensor = PositionFix("p", cov=0.25 * np.eye(2))
    cv = ConstantVelocity(q=0.1)
    p = np.array([[0.7, 0.2, 0.1], [0.3, 0.5, 0.2], [0.1, 0.1, 0.8]])
    imm = InteractingMultipleModel([cv] * 3, p, [sensor], initial_probs=[1.0, 0.0, 0.0])
    kf = KalmanFilter(cv, [sensor])
    prior = Gaussian(np.zeros(4), 4.0 * np.eye(4))
    b, g, mu = imm.initialize(prior), prior, np.array([1.0, 0.0, 0.0])
    for k, z in enumerate(_track(2, 8)):
        m = [Measurement(float(k), "p", z)]
        b = imm.update(imm.predict(b, 1.0), m)
        g = kf.update(kf.predict(g, 1.0), m)
        mu = mu @ p
        np.testing.assert_allclose(b.probs, mu, rtol=1e-12)
        np.testing.assert_allclose(b.combined().mean, g.mean, rtol=1e-10, atol=1e-10)


def test_batch_equals_separate_runs() -> None:
    sensor = PositionFix("p", cov=0.25 * np.eye(2))
    models = [ConstantVelocity(q=0.01), CoordinatedTurn(omega=0.3, q=0.01)]
    imm = InteractingMultipleModel(models, [[0.9, 0.1], [0.1, 0.9]], [sensor])
    tracks = [_track(s, 6) for s in (3, 4)]
    prior = Gaussian(np.zeros(4), np.eye(4))
    batched = imm.initialize(Gaussian(np.zeros((2, 4)), np.eye(4)))
    single = [imm.initialize(prior) for _ in tracks]
    for k in range(6):
        zs = np.stack([t[k] for t in tracks])
        batched = filter_step(imm, batched, 1.0, [Measurement(float(k), "p", zs)])
        single = [
            filter_step(imm, s, 1.0, [Measurement(float(k), "p", t[k])])
            for s, t in zip(single, tracks)
        ]
    for r in range(2):
        np.testing.assert_allclose(batched.means[r], single[r].means, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(batched.probs[r], single[r].probs, rtol=1e-10)


def test_turn_model_takes_over_during_a_turn() -> None:
    rng = np.random.default_rng(5)
    sensor = PositionFix("p", cov=0.01 * np.eye(2))
    turn = CoordinatedTurn(omega=0.4, q=1e-4)
    cv = ConstantVelocity(q=1e-4)
    imm = InteractingMultipleModel([cv, turn], [[0.95, 0.05], [0.05, 0.95]], [sensor])
    x = np.array([0.0, 0.0, 2.0, 0.0])
    b = imm.initialize(Gaussian(x, 0.01 * np.eye(4)))
    probs = []
    for k in range(20):
        x = (cv if k < 8 else turn).mean(x, 1.0)
        z = x[:2] + 0.1 * rng.standard_normal(2)
        b = filter_step(imm, b, 1.0, [Measurement(float(k), "p", z)])
        probs.append(b.probs[1])
    assert max(probs[:8]) < 0.5
    assert min(probs[12:]) > 0.9


def test_bad_configuration_is_named() -> None:
    sensor = PositionFix("p", cov=np.eye(2))
    with pytest.raises(ConfigError, match="transition"):
        InteractingMultipleModel([ConstantVelocity()], [[0.5]], [sensor])
    with pytest.raises(ConfigError, match="dim"):
        InteractingMultipleModel(
            [ConstantVelocity(), RandomWalk(dim=2)], [[0.5, 0.5], [0.5, 0.5]], [sensor]
        )
    assert isinstance(
        InteractingMultipleModel([ConstantVelocity()], [[1.0]], [sensor]).initialize(
            Gaussian(np.zeros(4), np.eye(4))
        ),
        IMMBelief,
    )
