"""The numeric simulation of Nott (2009, Sec. 5.1): a person walks, a camera and a radio tag
report, and six trackers estimate the foot position.

Truth: constant velocity or constant acceleration (the thesis's two "synthetic data" models)
with white acceleration noise, starting at (1, 1) m with the thesis's measured walking velocity
3 ft/s x 2 ft/s (0.9144, 0.6096) m/s; height 1.75 m, width 0.5 m + 5 cm of gait variation.
Measurements: the camera's V8/V4/V2 pixels with 1 px noise and the tag's position with
0.6 m / 0.4 m noise (Nott 2009, Sec. 5.1: both standard deviations). The camera is blind in the
occlusion window; the tag may report only every k-th frame, or on its own jittered clock with a
clock offset (event-driven mode, Nott 2009, Sec. 3.2.2).

Trackers (spec Sec. 3.11): B1 raw tag, B2 Kalman filter on the tag, B3 raw visual (the measured
foot pixel back-projected through H_f), B4 visual EKF (prediction only while occluded), B5
switching (B4 when visible, B2 while occluded), J the joint EKF (predict, tag update, camera
update; Nott 2009, Eqs. 3.32-3.36 as corrected in the spec).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ...core import Gaussian, Measurement
from ...filters import ExtendedKalmanFilter, KalmanFilter, run_filter
from ...motion import WalkingPerson, WalkingPersonCA
from ...sensors import (
    HomographyCamera,
    PositionFix,
    StackedSensor,
    back_project,
    default_camera,
    ground_homography,
)

METHODS = ("B1", "B2", "B3", "B4", "B5", "J")
METHOD_NAMES = {
    "B1": "RFID raw",
    "B2": "RFID KF",
    "B3": "visual raw",
    "B4": "visual EKF",
    "B5": "switching",
    "J": "joint EKF",
}
V0 = (0.9144, 0.6096)  # 3 ft/s and 2 ft/s (Nott 2009, Sec. 5.1)


@dataclass(frozen=True)
class SimConfig:
    """One simulation set-up (defaults: spec Sec. 6.3)."""

    dynamics: str = "ca"
    n_steps: int = 50
    dt: float = 0.2
    occ_start: int = 20
    occ_len: int = 0
    rfid_every: int = 1
    variant: str = "corners"
    mode: str = "grid"  # "grid": tag on the frame clock; "event": own jittered clock
    rfid_rate: float = 5.0  # Hz (event mode)
    rfid_jitter: float = 0.0  # s, std of the tag's sampling-time jitter (event mode)
    clock_offset: float = 0.0  # s, tag clock minus camera clock (event mode)
    stacked: bool = False
    filter_model: str = "cv"  # "ca": the spec's optional 8-D constant-acceleration filter
    sigma_a_truth: float = 0.2
    accel: tuple[float, float] = (-0.10, 0.05)
    rfid_sigma: tuple[float, float] = (0.6, 0.4)
    sigma_px: float = 1.0
    q_a: float = 0.5
    q_h: float = 1e-3
    q_w: float = 0.05

    @classmethod
    def from_mapping(cls, m: Mapping[str, Any]) -> SimConfig:
        known = {k: v for k, v in m.items() if k in cls.__dataclass_fields__}
        if "accel" in known:
            known["accel"] = tuple(known["accel"])
        if "rfid_sigma" in known:
            known["rfid_sigma"] = tuple(known["rfid_sigma"])
        return replace(cls(), **known)

    @property
    def times(self) -> np.ndarray:
        return self.dt * np.arange(self.n_steps)

    def occluded(self) -> np.ndarray:
        k = np.arange(self.n_steps)
        return (k >= self.occ_start) & (k < self.occ_start + self.occ_len)


def simulate_truth(cfg: SimConfig, rng: np.random.Generator) -> np.ndarray:
    """True states ``(T, 6)`` ``[x, y, h, w, vx, vy]`` at the frame times."""
    T, dt = cfg.n_steps, cfg.dt
    acc = np.asarray(cfg.accel) if cfg.dynamics == "ca" else np.zeros(2)
    pos = np.empty((T, 2))
    vel = np.empty((T, 2))
    pos[0], vel[0] = (1.0, 1.0), V0
    for k in range(1, T):
        a = acc + cfg.sigma_a_truth * rng.standard_normal(2)
        pos[k] = pos[k - 1] + vel[k - 1] * dt + 0.5 * a * dt * dt
        vel[k] = vel[k - 1] + a * dt
    t = cfg.times
    h = np.full(T, 1.75)
    w = 0.5 + 0.05 * np.sin(2 * np.pi * t / 1.0)
    return np.column_stack([pos, h, w, vel])


def sensors(cfg: SimConfig) -> dict[str, Any]:
    P = default_camera().P
    cam = HomographyCamera("camera", camera_matrix=P, variant=cfg.variant, sigma_px=cfg.sigma_px)  # type: ignore[arg-type]
    tag = PositionFix("tag", cov=np.diag(np.square(cfg.rfid_sigma)), position_index=(0, 1))
    return {"tag": tag, "camera": cam}


def simulate_measurements(
    cfg: SimConfig, truth: np.ndarray, rng: np.random.Generator
) -> tuple[list[Measurement], list[Measurement]]:
    """Tag and camera reports (lists of :class:`Measurement`), occlusion and rates applied."""
    sens = sensors(cfg)
    cam = sens["camera"]
    t = cfg.times
    y = cam.predict(truth) + cfg.sigma_px * rng.standard_normal((cfg.n_steps, cam.dim))
    occ = cfg.occluded()
    cams = [Measurement(float(t[k]), "camera", y[k]) for k in range(cfg.n_steps) if not occ[k]]
    sig = np.asarray(cfg.rfid_sigma)
    tags: list[Measurement] = []
    if cfg.mode == "grid":
        z = truth[:, :2] + sig * rng.standard_normal((cfg.n_steps, 2))
        tags = [
            Measurement(float(t[k]), "tag", z[k]) for k in range(0, cfg.n_steps, cfg.rfid_every)
        ]
    else:
        period = 1.0 / cfg.rfid_rate
        tau = np.arange(0.0, t[-1] + 1e-9, period)
        noise = rng.standard_normal((tau.size, 2))  # drawn first: jitter 0 at the frame rate = grid
        if cfg.rfid_jitter > 0:
            tau = np.sort(
                np.clip(tau + cfg.rfid_jitter * rng.standard_normal(tau.size), 0.0, t[-1])
            )
        # true position at the tag's sampling instant: the frame before, moved on with its velocity
        k = np.clip(np.searchsorted(t, tau + 1e-9, side="right") - 1, 0, cfg.n_steps - 1)
        p = truth[k, :2] + truth[k, 4:6] * (tau - t[k])[:, None]
        z = p + sig * noise
        stamps = np.clip(tau + cfg.clock_offset, 0.0, None)
        tags = [Measurement(float(s), "tag", zz) for s, zz in zip(stamps, z)]
    return tags, cams


def prior(cfg: SimConfig, z0: np.ndarray) -> Gaussian:
    """``x0 = (z_0, 1.70, 0.5, 0, 0)``, ``P0 = diag(1, 1, 0.01, 0.04, 1, 1)`` (spec Sec. 6.3)."""
    return Gaussian(
        np.array([z0[0], z0[1], 1.70, 0.5, 0.0, 0.0]), np.diag([1, 1, 0.01, 0.04, 1, 1.0])
    )


def _merge(tags: list[Measurement], cams: list[Measurement]) -> list[Measurement]:
    """Time order; at equal times the tag first (the thesis's order: RFID, then visual)."""
    both = [(m.time, 0, m) for m in tags] + [(m.time, 1, m) for m in cams]
    return [m for _, _, m in sorted(both, key=lambda r: (r[0], r[1]))]


def _stack(ms: list[Measurement], sid: str) -> list[Measurement]:
    """Tag and camera reports at the same time as one stacked report."""
    out: list[Measurement] = []
    i = 0
    while i < len(ms):
        m = ms[i]
        if (
            i + 1 < len(ms)
            and m.sensor_id == "tag"
            and ms[i + 1].sensor_id == "camera"
            and abs(ms[i + 1].time - m.time) < 1e-9
        ):
            out.append(Measurement(m.time, sid, np.concatenate([m.value, ms[i + 1].value])))
            i += 2
        else:
            out.append(m)
            i += 1
    return out


def _track(
    filt: Any, pri: Gaussian, ms: list[Measurement], t: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    tr = run_filter(filt, pri, ms, times=t, t0=0.0)
    keep = np.isin(np.round(tr.times, 9), np.round(t, 9))
    assert tr.covariances is not None
    return tr.means[keep], tr.covariances[keep]


def run_trackers(cfg: SimConfig, truth: np.ndarray, rng: np.random.Generator) -> dict[str, Any]:
    """Simulate the reports and run B1-B5 and J; positions ``(T, 2)`` per method, J's covariances."""
    tags, cams = simulate_measurements(cfg, truth, rng)
    sens = sensors(cfg)
    cam = sens["camera"]
    t = cfg.times
    motion: WalkingPerson | WalkingPersonCA = WalkingPerson(
        q_a=cfg.q_a, q_h=cfg.q_h, q_w=cfg.q_w, step=cfg.dt
    )
    z0 = tags[0].value if tags else truth[0, :2]
    pri = prior(cfg, z0)
    if cfg.filter_model == "ca":
        motion = WalkingPersonCA(q_j=0.05, q_h=cfg.q_h, q_w=cfg.q_w, step=cfg.dt)
        pri = Gaussian(
            np.append(pri.mean, [0.0, 0.0]), np.diag([1, 1, 0.01, 0.04, 1, 1, 0.25, 0.25])
        )
    occ = cfg.occluded()
    est: dict[str, np.ndarray] = {}

    # B1: the latest tag report (held between reports)
    tag_t = np.array([m.time for m in tags])
    tag_z = np.array([m.value for m in tags])
    idx = np.clip(np.searchsorted(tag_t, t + 1e-9, side="right") - 1, 0, len(tags) - 1)
    est["B1"] = tag_z[idx]
    # B3: the measured foot pixel back-projected through H_f (held while occluded)
    Hf = ground_homography(default_camera().P)
    foot_px = np.full((cfg.n_steps, 2), np.nan)
    frame_of = {round(m.time, 9): k for k, m in enumerate(cams)}
    for k, tk in enumerate(t):
        j = frame_of.get(round(float(tk), 9))
        if j is None:
            continue
        v = cams[j].value
        foot_px[k] = ((v[0] + v[2]) / 2, v[1]) if cfg.variant == "corners" else v[:2]
    b3 = back_project(Hf, foot_px)
    for k in range(1, cfg.n_steps):
        if not np.isfinite(b3[k]).all():
            b3[k] = b3[k - 1]
    est["B3"] = b3
    # B2 (tag KF), B4 (visual EKF), J (joint EKF)
    est["B2"] = _track(KalmanFilter(motion, {"tag": sens["tag"]}), pri, tags, t)[0][:, :2]
    est["B4"] = _track(ExtendedKalmanFilter(motion, {"camera": cam}), pri, cams, t)[0][:, :2]
    merged = _merge(tags, cams)
    if cfg.stacked:
        stacked = StackedSensor("tag+camera", [sens["tag"], cam])
        filt = ExtendedKalmanFilter(motion, {**sens, "tag+camera": stacked})
        jm, jc = _track(filt, pri, _stack(merged, "tag+camera"), t)
    else:
        jm, jc = _track(ExtendedKalmanFilter(motion, sens), pri, merged, t)
    est["J"] = jm[:, :2]
    est["B5"] = np.where(occ[:, None], est["B2"], est["B4"])
    return {"est": est, "J_cov": jc[:, :2, :2], "J_state": jm, "occluded": occ}


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    """One Monte Carlo run: rows per method and frame (errors in metres)."""
    cfg = SimConfig.from_mapping(config)
    rng = np.random.default_rng(seed)
    truth = simulate_truth(cfg, rng)
    out = run_trackers(cfg, truth, rng)
    rows = []
    err_j = out["est"]["J"] - truth[:, :2]
    nees = np.einsum("ki,kij,kj->k", err_j, np.linalg.inv(out["J_cov"]), err_j)
    for method, e in out["est"].items():
        d = e - truth[:, :2]
        err = np.linalg.norm(d, axis=1)
        for k in range(cfg.n_steps):
            rows.append(
                {
                    "case": config.get("case", ""),
                    "method": method,
                    "step": k,
                    "time": float(cfg.times[k]),
                    "occluded": bool(out["occluded"][k]),
                    "x": float(e[k, 0]),
                    "y": float(e[k, 1]),
                    "true_x": float(truth[k, 0]),
                    "true_y": float(truth[k, 1]),
                    "err": float(err[k]),
                    "nees": float(nees[k]) if method == "J" else np.nan,
                }
            )
    return rows


__all__ = ["METHODS", "METHOD_NAMES", "SimConfig", "run_once", "run_trackers", "simulate_truth"]
