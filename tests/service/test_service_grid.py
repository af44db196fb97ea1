"""The grid tracker in the node (Kushwaha 2010 SBE): microphone beam energies and camera column
scores (detection functions) and a camera's image positions (through its homography) fused on
the grid; live equals an offline run of the grid filter over the same readings. Image positions
through the EKF equal run_filter's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusetrack.core import ConfigError, Filter, Measurement, SteppingFilter
from fusetrack.filters import run_filter
from fusetrack.filters.grid import DirectionalMotion, GridFilter, GridSpec, map_sensors
from fusetrack.sensors import HomographyCamera
from fusetrack.sensors.detection_function import (
    AngularSampling,
    arc_mean_matrix,
    cell_arcs,
    normalize_likelihood,
)
from fusetrack.service.config import parse_config
from fusetrack.service.engine import FusionEngine, build_engine, build_filter
from fusetrack.service.node import FusionNode
from fusetrack.service.schema import SensorMessage, reading_from_vector

RATE, DURATION = 4.0, 10.0
MICS = {"mic_a": (0.0, 0.0), "mic_b": (40.0, 0.0)}
CAM = {"position": (20.0, 30.0), "heading": -math.pi / 2, "fov": math.radians(60), "cells": 64}


def _homography():
    """Ground plane (m) -> image (px) of a 500 px camera at (20, -10, 8) looking up the field."""
    c = np.array([20.0, -10.0, 8.0])
    f = np.array([0.0, 1.0, -0.4]) / np.linalg.norm([0.0, 1.0, -0.4])
    r = np.array([1.0, 0.0, 0.0])
    d = np.cross(f, r)
    rot = np.vstack([r, d, f])
    p = np.array([[500.0, 0, 320], [0, 500.0, 240], [0, 0, 1]]) @ np.hstack(
        [rot, -rot @ c[:, None]]
    )
    return p[:, [0, 1, 3]]


def _truth(t):
    return np.array([8.0 + 1.2 * t, 10.0 + 0.5 * t])


def _network(filter="grid", with_functions=True):
    sensors = [
        {
            "id": "cam_img",
            "kind": "image_position",
            "homography": _homography().tolist(),
            "sigma_px": 2.0,
        },
    ]
    if with_functions:
        sensors += [
            {"id": sid, "kind": "detection_function", "position": list(p), "cells": 36}
            for sid, p in MICS.items()
        ]
        sensors.append(
            {
                "id": "cam_cols",
                "kind": "detection_function",
                "position": list(CAM["position"]),
                "heading": CAM["heading"],
                "fov": CAM["fov"],
                "cells": CAM["cells"],
            }
        )
    else:
        sensors.append({"id": "tag", "kind": "position_fix", "cov": [[4.0, 0.0], [0.0, 4.0]]})
    return parse_config(
        {
            "area": [0, 40, 0, 30],
            "sensors": sensors,
            "nodes": [
                {
                    "id": f"n-{s['id']}",
                    "key": f"test-key-{s['id']}-0000000001",
                    "sensors": [s["id"]],
                }
                for s in sensors
            ],
            "fusion": {"rate_hz": RATE, "clock": "data", "lag": 0.5, "idle_flush": 0.3},
            "tracker": {
                "filter": filter,
                "prior_mean": [8, 10, 0, 0],
                "prior_std": [3, 3, 2, 2],
                "grid": {"cell": 1.0, "delta": 1.0},
            },
        }
    )


def _readings(cfg, seed=0):
    """(time, sensor, value): every sensor once per tick, 0.1 s before it."""
    rng = np.random.default_rng(seed)
    cam = cfg.sensor_models()["cam_img"]
    out = []
    for k in range(1, round(DURATION * RATE) + 1):
        t = k / RATE - 0.1
        p = _truth(t)
        for s in cfg.sensors:
            if s.kind == "image_position":
                z = cam.predict(p) + 2.0 * rng.standard_normal(2)
            elif s.kind == "position_fix":
                z = p + 2.0 * rng.standard_normal(2)
            else:
                d = p - np.array(s.position)
                theta = math.atan2(d[1], d[0]) - s.heading  # in the sensor's frame
                angles = s.sampling().angles
                off = np.angle(np.exp(1j * (angles - theta)))
                width = 0.25 if s.cells == 36 else 0.03  # beams are wide, columns narrow
                z = 1.0 + 5.0 * np.exp(-0.5 * (off / width) ** 2)
                z = np.maximum(z + 0.2 * rng.standard_normal(z.size), 0.0)
            out.append((t, s.id, np.asarray(z, float)))
    return out


def _live(cfg, readings):
    clock = [0.0]
    node = FusionNode(cfg, wall=lambda: clock[0])
    owner, kinds = cfg.owner(), {s.id: s.kind for s in cfg.sensors}
    for i, (t, sid, z) in enumerate(readings):
        m = SensorMessage(
            node=owner[sid],
            seq=i + 1,
            sensor=sid,
            time=t,
            reading=reading_from_vector(kinds[sid], z),
        )
        out = node.ingest_message(m, owner[sid])
        assert out.accepted, out
    states = node.advance()
    clock[0] += 1.0
    return node, states + node.advance()


def _offline_grid(cfg, readings, ticks):
    """The grid filter run directly over the same readings, with each sensor's per-cell likelihood
    built by hand: Eq. 32 arc means for the detection functions, the camera's Gaussian for the
    image positions."""
    grid = GridSpec(0, 40, 0, 30, 1.0)
    filt = GridFilter(
        grid,
        map_sensors(grid, [s.id for s in cfg.sensors]),
        "product",
        motion=DirectionalMotion(1.0),
        first_delta=2.0,
        max_speed=20.0,
    )
    u = (grid.centres - [8.0, 10.0]) / 3.0
    belief = filt.initial(np.exp(-0.5 * np.sum(u * u, axis=1)))
    cam = HomographyCamera("cam_img", foot_homography=_homography(), variant="foot", sigma_px=2.0)
    weights = {}
    for s in cfg.sensors:
        if s.kind == "detection_function":
            lo, hi, _ = cell_arcs(s.position, s.heading, grid.centres, 0.5)
            sampling = (
                AngularSampling.beams(36)
                if s.cells == 36
                else AngularSampling.camera_bins(s.fov, s.cells)
            )
            weights[s.id] = arc_mean_matrix(sampling, lo, hi)
    states4 = np.zeros((grid.size, 4))
    states4[:, :2] = grid.centres
    means = []
    for k in ticks:
        maps = []
        for t, sid, z in readings:
            if not (k - 1) / RATE < t <= k / RATE:
                continue
            if sid in weights:
                lik = normalize_likelihood(weights[sid] @ z)
                q = (z - z.min()).max() / (z - z.min()).sum()
            else:
                ll = cam.log_likelihood(z, states4)
                lik = normalize_likelihood(np.exp(ll - ll.max()))
                q = (lik - lik.min()).max() / (lik - lik.min()).sum()
            maps.append(Measurement(k / RATE, sid, lik, metadata={"quality": q}))
        belief = filt.step(belief, 1 / RATE, maps)
        means.append(belief.mean)
    return np.array(means)


def test_grid_tracker_fuses_detection_functions_and_image_positions():
    cfg = _network()
    readings = _readings(cfg)
    node, states = _live(cfg, readings)
    assert [s.tick for s in states] == list(
        range(1, 40)
    )  # the last readings (9.9 s) wait and node.rejected.total() == 0
    assert states[-1].sensors == ["cam_cols", "cam_img", "mic_a", "mic_b"]
    offline = _offline_grid(cfg, readings, range(1, 40))
    np.testing.assert_allclose([s.position for s in states], offline, rtol=0, atol=1e-9)
    truth = np.array([_truth(s.time) for s in states])
    err = np.linalg.norm(np.array([s.position for s in states]) - truth, axis=1)
    assert np.sqrt(np.mean(err[8:] ** 2)) < 1.0  # cells are 1 m; standing still: ~9 m at the end
    cov = np.array(states[-1].position_covariance)
    assert np.all(np.linalg.eigvalsh(cov) > 0) and np.sqrt(np.trace(cov)) < 2.0
    assert node.tracks_view()["tracks"][0]["position"] == states[-1].position


def test_the_grid_filter_runs_in_the_one_engine():
    """No engine of its own: the node's engine steps the grid filter like any other Filter."""
    cfg = _network()
    engine = build_engine(cfg, 0.0)
    assert type(engine) is FusionEngine
    assert isinstance(engine.filter, GridFilter) and isinstance(engine.filter, SteppingFilter)
    assert isinstance(build_filter(_network("ekf", with_functions=False)), Filter)


def test_each_grid_input_alone_tracks():
    """Each kind of input carries the target on its own (a wrong arc or sign would not)."""
    cfg = _network()
    readings = _readings(cfg, seed=3)
    # measured: 0.23, 0.54 and 2.2 m; one microphone alone: 13 m, one camera's columns: 8.7 m
    for keep, bound in (
        (("mic_a", "mic_b"), 1.0),
        (("cam_img",), 1.0),
        (("mic_a", "cam_cols"), 3.5),
    ):
        _, states = _live(cfg, [r for r in readings if r[1] in keep])
        truth = np.array([_truth(s.time) for s in states])
        err = np.linalg.norm(np.array([s.position for s in states]) - truth, axis=1)
        assert np.sqrt(np.mean(err[8:] ** 2)) < bound, keep


def test_image_positions_through_the_ekf_equal_run_filter():
    cfg = _network("ekf", with_functions=False)
    readings = _readings(cfg, seed=1)
    _, states = _live(cfg, readings)
    ticks = np.array([s.time for s in states])
    ms = [Measurement(t, sid, z) for t, sid, z in readings]
    track = run_filter(build_filter(cfg), cfg.tracker.prior(), ms, times=ticks, t0=0.0)
    keep = np.isin(np.round(track.times, 9), np.round(ticks, 9))
    np.testing.assert_allclose([s.state for s in states], track.means[keep], atol=1e-9)
    err = np.linalg.norm(
        np.array([s.position for s in states]) - [_truth(t) for t in ticks], axis=1
    )
    assert np.sqrt(np.mean(err[8:] ** 2)) < 1.0


def test_detection_functions_need_the_grid_tracker():
    with pytest.raises(ConfigError, match="grid"):
        _network("ekf")


def test_a_grid_too_fine_for_the_area_is_refused():
    cfg = _network()
    data = cfg.model_dump()
    data["tracker"]["grid"]["cell"] = 0.01  # 4000 x 3000 cells
    data["nodes"] = [dict(n) for n in data["nodes"]]
    with pytest.raises(ConfigError, match=r"tracker\.grid\.cell"):
        parse_config(data)
