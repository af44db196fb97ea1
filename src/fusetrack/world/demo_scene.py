"""The demo scene: one manoeuvring target, two microphone arrays, a camera and a radio tag.

A target moves in a 100 m x 60 m area under the coordinated-turn model with the turn rate in the
state (so it turns, and the turn rate itself wanders), starting from a draw of the prior. Two
microphone arrays report bearings every step, a camera reports a sharp bearing while the target
is inside its field of view and not behind an occluder, and a radio tag reports a noisy position
fix every ``tag_period`` seconds. The demo experiment (:mod:`fusetrack.experiments.demo`) and the
live node's ``demo`` replay (:mod:`fusetrack.service.replay`) both simulate this scene.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core import Gaussian, Measurement
from ..motion import CoordinatedTurnRate
from ..sensors import Bearing, PositionFix

AREA = (0.0, 100.0, 0.0, 60.0)
"""The area ``(x0, x1, y0, y1)`` the target moves in (m)."""


@dataclass(frozen=True)
class DemoScene:
    """Everything the demo's world and sensors are made of (SI units, radians)."""

    dt: float = 0.5
    duration: float = 60.0
    q: float = 0.05  # acceleration noise PSD (m^2/s^3)
    q_omega: float = 2e-4  # turn-rate noise PSD (rad^2/s^3)
    prior_mean: tuple[float, ...] = (20.0, 20.0, 1.5, 0.8, 0.02)
    prior_std: tuple[float, ...] = (2.0, 2.0, 0.5, 0.5, 0.02)
    sigma_mic: float = np.deg2rad(3.0)
    sigma_camera: float = np.deg2rad(0.5)
    camera_fov: float = np.deg2rad(70.0)
    occluded: tuple[tuple[float, float], ...] = ((18.0, 26.0), (40.0, 46.0))
    tag_period: float = 2.0
    tag_cov: tuple[tuple[float, float], tuple[float, float]] = ((4.0, 1.2), (1.2, 2.25))

    @property
    def times(self) -> np.ndarray:
        return self.dt * np.arange(1, round(self.duration / self.dt) + 1)

    def motion(self) -> CoordinatedTurnRate:
        return CoordinatedTurnRate(q=self.q, q_omega=self.q_omega)

    def prior(self) -> Gaussian:
        return Gaussian(np.array(self.prior_mean), np.diag(np.square(self.prior_std)))

    def sensors(self) -> dict[str, Any]:
        return {
            "mic_west": Bearing("mic_west", position=[0.0, 0.0], sigma=self.sigma_mic),
            "mic_east": Bearing("mic_east", position=[100.0, 0.0], sigma=self.sigma_mic),
            "camera": Bearing(
                "camera",
                position=[50.0, 62.0],
                sigma=self.sigma_camera,
                heading=-np.pi / 2,
                fov=self.camera_fov,
            ),
            "tag": PositionFix("tag", cov=np.array(self.tag_cov)),
        }

    def reports_at(self, sensor_id: str, t: float) -> bool:
        """Whether ``sensor_id`` may report at time ``t``: the tag every ``tag_period``, the
        camera except while an occluder hides the target, the microphones always."""
        if sensor_id == "tag":
            return bool(np.isclose(t % self.tag_period, 0.0))
        if sensor_id == "camera":
            return not any(a <= t < b for a, b in self.occluded)
        return True


def simulate_demo(
    scene: DemoScene, rng: np.random.Generator
) -> tuple[np.ndarray, list[Measurement]]:
    """A true trajectory ``(T + 1, 5)`` (row 0: the initial state at t = 0, drawn from the prior)
    drawn from the motion model, and the reports of every sensor at ``scene.times``."""
    motion, sensors = scene.motion(), scene.sensors()
    x = scene.prior().sample(rng)
    truth, reports = [x], []
    for t in scene.times:
        x = motion.sample(x, scene.dt, rng)
        truth.append(x)
        for sid, sensor in sensors.items():
            if not scene.reports_at(sid, t):
                continue
            z = sensor.simulate(x, rng)
            if np.all(np.isfinite(z)):
                reports.append(Measurement(float(t), sid, z))
    return np.array(truth), reports
