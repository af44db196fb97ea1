"""Shared scenarios of the tracker tests: two constant-velocity targets in a 200 m square with
Poisson clutter, the tracker that follows them, and the same recording with a flood of false
alarms."""

from __future__ import annotations

import numpy as np

from fusetrack.association import GlobalNearestNeighbour
from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import KalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import LinearGaussianSensor
from fusetrack.tracking import (
    InverseMeasurementPrior,
    MissedCountDeleter,
    MofNInitiator,
    MultiTargetTracker,
)

H_POS = np.hstack([np.eye(2), np.zeros((2, 2))])
SIGMA = 0.5  # measurement noise std per axis (m)
SIDE = 200.0  # the surveillance square (m)
CLUTTER_RATE = 2.0  # false alarms per scan, uniform over the square
MOTION = ConstantVelocity(ndim=2, q=0.05)
POS = LinearGaussianSensor("pos", H=H_POS, R=SIGMA**2 * np.eye(2))
WIDE = Gaussian(np.zeros(4), np.diag([0.0, 0.0, 9.0, 9.0]))  # velocity std 3 m/s


def tracker(initiator=None, deleter=None, p_detect=0.9, **kw):
    kf = kw.pop("filt", KalmanFilter(MOTION, [POS]))
    return MultiTargetTracker(
        kf,
        [POS],
        GlobalNearestNeighbour(),
        initiator or MofNInitiator(3, 4, InverseMeasurementPrior([POS], WIDE)),
        deleter or MissedCountDeleter(3),
        p_detect=p_detect,
        clutter_density=CLUTTER_RATE / SIDE**2,
        gate_probability=kw.pop("gate_probability", 0.999),
        **kw,
    )


def scenario(seed, n_scans=40, p_detect=0.9, clutter=CLUTTER_RATE, last_scan=(None, None)):
    """Two constant-velocity targets (truth drawn from MOTION), position reports with
    probability ``p_detect``, Poisson clutter; target ``i`` reports up to ``last_scan[i]``.
    Returns the measurements, the truth ``(2, n_scans, 4)`` and each measurement's source
    (0, 1, or -1 for clutter)."""
    rng = np.random.default_rng(seed)
    x = np.array([[20.0, 20.0, 2.0, 1.0], [180.0, 180.0, -1.0, -1.5]])
    truth, zs, source = [], [], []
    for k in range(n_scans):
        if k:
            x = MOTION.sample(x, 1.0, rng)
        truth.append(x.copy())
        for i in range(2):
            alive = last_scan[i] is None or k <= last_scan[i]
            if alive and rng.random() < p_detect:
                zs.append(Measurement(k, "pos", x[i, :2] + SIGMA * rng.standard_normal(2)))
                source.append(i)
        for _ in range(rng.poisson(clutter)):
            zs.append(Measurement(k, "pos", rng.uniform(0.0, SIDE, 2)))
            source.append(-1)
    return zs, np.stack(truth, axis=1), np.array(source)


def with_flood(seed=3, at=6, n=5000):
    """Two targets over 10 scans (:func:`scenario`) and ``n`` uniform false alarms more in scan
    ``at`` (the recording is then out of time order: run it with ``order="reorder"``)."""
    zs, _, _ = scenario(seed=seed, n_scans=10)
    flood = np.random.default_rng(99).uniform(0.0, SIDE, (n, 2))
    return zs + [Measurement(float(at), "pos", z) for z in flood]
