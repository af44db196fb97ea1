"""CPF-SP: the batched bank step over translated sensor copies equals the loop over sensors."""

import numpy as np

from fusetrack.core import Gaussian
from fusetrack.filters import run_filter
from fusetrack.filters.cpf_sp import CPFSPProposal, commutes_with_translation, translated_copies
from fusetrack.filters.sis import ProposalParticleFilter, sensor_measurements
from fusetrack.motion import ConstantVelocity
from fusetrack.motion.benchmark import ScalarBenchmark
from fusetrack.sensors import Bearing, Range


def _scenario(seed: int) -> tuple[list[Bearing], list[list[np.ndarray | None]], Gaussian]:
    rng = np.random.default_rng(seed)
    sensors = [Bearing(f"d{k}", position=[30.0 * k, 10.0 * (k % 2)], sigma=0.05) for k in range(4)]
    cv = ConstantVelocity(q=0.05, noise="discrete")
    x, zs = np.array([5.0, 20.0, 3.0, 0.5]), []
    for t in range(12):
        x = cv.sample(x, 1.0, rng)
        # a changing subset of active sensors, as with power-aware activation
        zs.append([s.simulate(x, rng) if (t + k) % 3 else None for k, s in enumerate(sensors)])
    return sensors, zs, Gaussian(np.array([5.0, 20.0, 3.0, 0.5]), np.diag([4.0, 4.0, 0.5, 0.5]))


def test_batched_banks_equal_the_loop() -> None:
    sensors, zs, prior = _scenario(3)
    motion = ConstantVelocity(q=0.05)
    out = []
    for batch in (True, False):
        f = ProposalParticleFilter(motion, sensors, CPFSPProposal(6, batch_sensors=batch), 100)
        ms = [m for k, step in enumerate(zs) for m in sensor_measurements(sensors, step, k + 1.0)]
        out.append(run_filter(f, prior, ms, rng=np.random.default_rng(11), t0=0.0).means)
    assert np.all(np.isfinite(out[0]))
    np.testing.assert_allclose(out[0], out[1], rtol=1e-10, atol=1e-10)


def test_translation_checks() -> None:
    sensors, _, _ = _scenario(0)
    pos = translated_copies(sensors)
    assert pos is not None and pos.shape == (4, 2)
    other = [*sensors[:2], Bearing("x", position=[0.0, 0.0], sigma=0.2)]
    assert translated_copies(other) is None
    assert translated_copies([sensors[0], Range("r", position=[0.0, 0.0], sigma=0.05)]) is None
    assert commutes_with_translation(ConstantVelocity(), np.array([50.0, -20.0]))
    assert not commutes_with_translation(ScalarBenchmark(), np.array([2.0]))
