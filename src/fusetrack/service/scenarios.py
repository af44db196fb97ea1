"""Simulated scenarios for the grid tracker and for several targets, to replay into a node.

* ``two-targets`` (:func:`two_targets_network`, ``examples/network-targets.yaml``): two targets
  on circles, a radar at (50, -10) sending range-bearing plots of both every 0.25 s (each seen
  with probability 0.95, plus on average 0.1 false plot per scan); tracked by MCMCDA, whose
  model is one detecting sensor: at most one detection per target per tick (two sensors seeing
  the same target in one tick would give it two; fuse them first, e.g. on the grid).
* ``grid`` (:func:`grid_network`, ``examples/network-grid.yaml``): one target on an ellipse,
  two microphone arrays sending 36 beam energies, a camera sending 64 column scores and a
  camera sending the target's image position through its homography, every 0.25 s; tracked by
  the grid filter.

The detection functions are a bump at the target's direction over a noisy floor: beam energy
``1 + 5 exp(-off^2 / (2 * 0.25^2))`` (10 degree beams are wide), column score the same with a
0.03 rad width, plus N(0, 0.2^2) noise, clipped at 0.
"""

from __future__ import annotations

import math
import secrets
from typing import Any

import numpy as np

from .config import NetworkConfig, parse_config
from .replay import Recorded, Scenario

RATE = 4.0
RADAR = (50.0, -10.0)
MICS = {"mic_a": (0.0, 0.0), "mic_b": (40.0, 0.0)}
CAMERA_COLUMNS = {"position": [20.0, 30.0], "heading_deg": -90, "fov_deg": 60, "cells": 64}
GROUND_TO_IMAGE = [
    [500.0, 297.1125, -6078.1145],
    [0.0, 37.1391, 4798.3675],
    [0.0, 0.9285, 12.2559],
]  # a 500 px camera at (20, -10, 8) m looking up the field, 22 degrees down


def _keys(nodes: list[str], keys: dict[str, str] | None) -> dict[str, str]:
    return keys or {n: secrets.token_hex(16) for n in nodes}


def two_targets_network(keys: dict[str, str] | None = None, **fusion: Any) -> NetworkConfig:
    """The network of ``examples/network-targets.yaml`` (fresh keys unless given)."""
    k = _keys(["radar-node"], keys)
    return parse_config(
        {
            "area": [0, 100, 0, 60],
            "sensors": [
                {
                    "id": "radar",
                    "kind": "range_bearing",
                    "position": list(RADAR),
                    "sigma_range": 0.5,
                    "sigma_bearing_deg": 0.6,
                },
            ],
            "nodes": [
                {"id": "radar-node", "key": k["radar-node"], "sensors": ["radar"]},
            ],
            "fusion": {"rate_hz": RATE, "clock": "data", "lag": 0.5, "start": 0.0, **fusion},
            "tracker": {
                "prior_mean": [50, 30, 0, 0],
                "prior_std": [50, 30, 5, 5],
                "association": {
                    "method": "mcmcda",
                    "n_mc": 300,
                    "window": 8,
                    "p_detect": 0.95,
                    "false_alarm_rate": 0.1,
                    "birth_rate": 0.05,
                    "obs_std": 1.0,
                },
            },
        },
        "two-targets network",
    )


def two_targets_truth(t: np.ndarray) -> np.ndarray:
    """``(T, 2, 2)``: both targets' positions at times ``t`` (circles of 15 m, 60 s a turn,
    centres 40 m apart, turning opposite ways)."""
    a = 2 * np.pi * np.asarray(t, float)[:, None] / 60.0
    one = np.hstack([30 + 15 * np.cos(a), 30 + 15 * np.sin(a)])
    two = np.hstack([70 - 15 * np.cos(a), 30 + 15 * np.sin(a)])
    return np.stack([one, two], axis=1)


def two_targets_scenario(
    network: NetworkConfig, seed: int = 0, duration: float | None = None
) -> Scenario:
    """Radar plots of the two targets, with misses and false plots."""
    rng = np.random.default_rng(seed)
    n = round((60.0 if duration is None else duration) * RATE)
    times = np.arange(1, n + 1) / RATE - 0.05
    truth = two_targets_truth(times)
    radar = network.sensor("radar")
    sr, sb = float(radar.sigma_range or 0.0), float(radar.sigma_bearing or 0.0)
    x0, x1, y0, y1 = network.area
    out = []
    for k, t in enumerate(times):
        plots = [p for p in truth[k] if rng.random() < 0.95]
        plots += [
            np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)]) for _ in range(rng.poisson(0.1))
        ]
        for p in plots:
            d = p - RADAR
            r = math.hypot(*d) + sr * rng.standard_normal()
            b = math.atan2(d[1], d[0]) + sb * rng.standard_normal()
            out.append(Recorded(float(t), "radar", (r, b)))
    return Scenario(out, times, truth.reshape(n, 4), network)


def grid_network(keys: dict[str, str] | None = None, **fusion: Any) -> NetworkConfig:
    """The network of ``examples/network-grid.yaml`` (fresh keys unless given)."""
    k = _keys(["array-a", "array-b", "camera-1"], keys)
    sensors: list[dict[str, Any]] = [
        {"id": sid, "kind": "detection_function", "position": list(p), "cells": 36}
        for sid, p in MICS.items()
    ]
    sensors.append({"id": "cam_cols", "kind": "detection_function", **CAMERA_COLUMNS})
    sensors.append(
        {
            "id": "cam_img",
            "kind": "image_position",
            "homography": GROUND_TO_IMAGE,
            "sigma_px": 2.0,
            "image_size": [640, 480],
        }
    )
    return parse_config(
        {
            "area": [0, 40, 0, 30],
            "sensors": sensors,
            "nodes": [
                {"id": "array-a", "key": k["array-a"], "sensors": ["mic_a"]},
                {"id": "array-b", "key": k["array-b"], "sensors": ["mic_b"]},
                {"id": "camera-1", "key": k["camera-1"], "sensors": ["cam_cols", "cam_img"]},
            ],
            "fusion": {"rate_hz": RATE, "clock": "data", "lag": 0.5, "start": 0.0, **fusion},
            "tracker": {
                "filter": "grid",
                "grid": {"cell": 0.5, "delta": 1.0, "fusion": "product"},
                "prior_mean": [28, 15, 0, 0],
                "prior_std": [5, 5, 1, 1],
            },
        },
        "grid network",
    )


def grid_truth(t: np.ndarray) -> np.ndarray:
    """``(T, 2)``: an ellipse around the field's centre, 40 s a turn."""
    a = 2 * np.pi * np.asarray(t, float) / 40.0
    return np.stack([20 + 8 * np.cos(a), 15 + 6 * np.sin(a)], axis=1)


def detection_function(
    sampling_angles: np.ndarray, theta: float, width: float, rng: np.random.Generator
) -> np.ndarray:
    """A bump at ``theta`` (sensor frame) over a floor of 1, noisy, non-negative."""
    off = np.angle(np.exp(1j * (sampling_angles - theta)))
    z = 1.0 + 5.0 * np.exp(-0.5 * (off / width) ** 2) + 0.2 * rng.standard_normal(off.size)
    return np.asarray(np.maximum(z, 0.0), dtype=float)


def grid_scenario(network: NetworkConfig, seed: int = 0, duration: float | None = None) -> Scenario:
    """Beam energies, column scores and image positions of one target (module docstring)."""
    rng = np.random.default_rng(seed)
    n = round((40.0 if duration is None else duration) * RATE)
    times = np.arange(1, n + 1) / RATE - 0.05
    truth = grid_truth(times)
    models = network.sensor_models()
    out = []
    for k, t in enumerate(times):
        for s in network.sensors:
            if s.kind == "image_position":
                z = models[s.id].predict(truth[k]) + 2.0 * rng.standard_normal(2)
            else:
                assert s.position is not None
                d = truth[k] - np.asarray(s.position[:2])
                theta = math.atan2(d[1], d[0]) - s.heading
                width = 0.25 if s.fov >= 2 * math.pi - 1e-9 else 0.03
                z = detection_function(s.sampling().angles, theta, width, rng)
            out.append(Recorded(float(t), s.id, tuple(float(v) for v in z)))
    return Scenario(out, times, truth, network)


NETWORKS = {"two-targets": two_targets_network, "grid": grid_network}
