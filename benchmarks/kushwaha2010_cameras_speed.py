"""Speed of one Kushwaha 2010 Ch. V tracker step: 1000 particles, 10 cameras (issue 10).

Ten cameras on a ring all see the ellipsoid target; one T0 step draws 1000 synchronised 3-D
particles and every camera computes the HS and LBP histograms of the 1000 projected ellipses and
their Bhattacharyya similarities (Algorithm 2). Reported as CPU seconds per step (process time,
so other load on the machine matters less), its split, the paper's 4 Hz budget (250 ms) as a
ratio, and the ratio of the Numba region-histogram kernel to its NumPy reference on the same
regions. Also one step of T2 (mixture fit + in-network product) and of T4 (2-D mixtures + MAP).

The wall seconds of the same calls (each clock's fastest) are in ``"wall"``. BLAS and Numba at
their defaults (``--threads T``: T threads for both, ``_results.py``). fusetrack only: no peer.

    python benchmarks/kushwaha2010_cameras_speed.py [--repeats 3] [--particles 1000]
        [--threads T] [--json] [--save | --out PATH]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from fusetrack.core import filter_step
from fusetrack.experiments.kushwaha2010.cameras import appearance_model
from fusetrack.filters.smart_camera_trackers import (
    CameraNetwork,
    ImagePlaneTracker,
    Particle3DTracker,
    TrackerSettings,
)
from fusetrack.perception.appearance import features_from_rgb
from fusetrack.sensors.appearance import N_HS, region_histograms, region_histograms_reference
from fusetrack.sensors.camera_geometry import PinholeCamera
from fusetrack.sensors.ellipsoid_camera import EllipsoidCamera, look_at
from fusetrack.world.ellipsoid_scene import Trajectory, render_frames

BUDGET_S = 0.25  # one step at the paper's 4 Hz


def ring(n: int = 10, radius: float = 6.0, focal: float = 200.0) -> list[EllipsoidCamera]:
    K = np.array([[focal, 0, 80.0], [0, focal, 60.0], [0, 0, 1.0]])
    cams = []
    for i in range(n):
        a = 2 * np.pi * i / n
        c = np.array([radius * np.cos(a), radius * np.sin(a), 2.5])
        cams.append(
            EllipsoidCamera(
                f"cam{i}", PinholeCamera(K, look_at(c, np.array([0, 0, 1.0])), c, 160, 120)
            )
        )
    return cams


_WALL: dict[str, float] = {}  # wall seconds of the _cpu calls, by label


def _cpu(fn, repeats: int, label: str | None = None) -> float:
    """Least CPU seconds of ``repeats`` calls; the least wall seconds go to ``_WALL[label]``."""
    both = _results.repeat(fn, repeats)
    if label is not None:
        _WALL[label] = both["wall"]
    return float(both["cpu"])


def measure(repeats: int = 3, particles: int = 1000) -> dict[str, float]:
    target, model = appearance_model()
    cams = ring()
    truth = Trajectory(
        np.array([[0.0, 0.0, 1.0], [0.05, 0.0, 1.0]]),
        np.array([[0.05, 0.0, 0.0]] * 2),
        np.array([[0.0, 0.0, 0.0, 1.0]] * 2),
    )
    frames = render_frames(cams, target, truth, np.random.default_rng(0))
    feats = [features_from_rgb(img) for img in frames.images[1]]
    net = CameraNetwork.build(cams, model, target.semi_axes, (7.0, 0.0, 0.0))
    measurements = net.measurements(1.0, feats)
    settings = TrackerSettings(n_particles=particles)
    init = (truth.positions[0], truth.velocities[0], truth.quaternions[0])
    rng = np.random.default_rng(1)

    def step(mode: str) -> None:
        if mode in ("T0", "T2"):
            tracker: Particle3DTracker | ImagePlaneTracker = Particle3DTracker(mode, net, settings)
        else:
            tracker = ImagePlaneTracker(mode, net, settings)
        filter_step(tracker, tracker.initial_belief(*init), 1.0, measurements, rng)

    step("T0")  # compile the Numba kernel
    out: dict[str, object] = {
        f"{m}_step_cpu_s": _cpu(lambda m=m: step(m), repeats, f"{m}_step_s")
        for m in ("T0", "T2", "T4")
    }
    out["T0_step_over_4Hz_budget"] = out["T0_step_cpu_s"] / BUDGET_S
    x = truth.positions[1] + 0.15 * rng.standard_normal((particles, 3))
    yc, B = cams[0].ellipse(x, truth.quaternions[1], target.semi_axes)
    fast = _cpu(lambda: region_histograms(feats[0].hs, yc, B, N_HS), repeats, "histograms_s")
    slow = _cpu(
        lambda: region_histograms_reference(feats[0].hs, yc[:100], B[:100], N_HS), 1, "ref_s"
    ) * (particles / 100)
    out["histograms_1000_regions_cpu_s"] = fast
    out["numpy_reference_over_numba"] = slow / max(fast, 1e-9)
    out["cameras"] = len(cams)
    out["particles"] = particles
    out["wall"] = {
        **{f"{m}_step_s": _WALL[f"{m}_step_s"] for m in ("T0", "T2", "T4")},
        "histograms_1000_regions_s": _WALL["histograms_s"],
        "numpy_reference_over_numba": _WALL["ref_s"]
        * particles
        / 100
        / max(_WALL["histograms_s"], 1e-9),
    }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--particles", type=int, default=1000)
    ap.add_argument("--json", action="store_true")
    _results.add_arguments(ap)
    args = ap.parse_args()
    (res,) = _results.measured(args, __file__, lambda: [measure(args.repeats, args.particles)])
    if args.json:
        print(json.dumps(res, indent=2))
        return
    for k, v in res.items():
        print(f"{k:32s} {v:.4g}" if isinstance(v, float) else f"{k:32s} {v}")


if __name__ == "__main__":
    main()
