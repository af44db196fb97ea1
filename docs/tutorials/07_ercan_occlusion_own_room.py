"""A paper's method in your own room: Ercan's occlusion-aware camera likelihood.

Ercan, El Gamal & Guibas (2013) track one person with many simple cameras in a room where other
people walk around and block the view. Each camera reports only where the person appears along
its image row — or nothing. The point of the paper is that *nothing* is information too: if a
camera that should see a spot reports nothing, the person is probably not there, unless one
of the other walkers stands in between. The likelihood of a step's reports (their Eq. 6)
therefore multiplies the Gaussian terms of the cameras that saw the person by the probability
of the seen / not-seen pattern, computed from what is known of where the other walkers are:

* `"perfect"`: their positions are known exactly;
* `"gaussian"`: a Gaussian prior on each (e.g. from a coarse tracker of the others);
* `"none"`: nothing is known — a not-seen report then only rules out spots no walker could
  hide (outside the camera's view, behind a wall).

In fusetrack that likelihood is a sensor model, `OcclusionAwareCameraSensor`, and the paper's
tracker (auxiliary SIR on a waypoint motion model, `WaypointASIR`) takes it like any other
sensor. Here we build *our own* room — a 80 x 50 floor with a cupboard in it, 6 cameras on the
walls of which 2 are read each step (the paper reads a few of many cameras to save bandwidth),
6 other people walking about — simulate the readings, and track with the three levels of
knowledge of the others. This is one run: the differences between the three are of the size
of run-to-run variation at this length; the paper's experiments, averaged over many runs, are
the `ercan2013-*` experiments (see the Ercan 2013 page).

Run: `python docs/tutorials/07_ercan_occlusion_own_room.py [--quick] [--out DIR]`.
"""

import argparse
import os
from pathlib import Path

import numpy as np

from fusetrack.core import Measurement
from fusetrack.evaluation.plots import plot_series
from fusetrack.filters import WaypointASIR
from fusetrack.motion import WaypointRegimeDynamics
from fusetrack.sensors import (
    CameraNetworkReport,
    OcclusionAwareCameraSensor,
    OcclusionAwareLikelihood,
    ring_of_cameras,
)
from fusetrack.world import OccluderPriors, Room, WaypointWalkers, disks_block, rectangle


def options() -> argparse.Namespace:
    """`--quick` (or `FUSETRACK_QUICK=1`) for a short run; `--out DIR` for the figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", default=os.environ.get("FUSETRACK_QUICK") == "1"
    )
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "figures")
    return parser.parse_args()


args = options()
steps = 40 if args.quick else 150
n_particles = 300 if args.quick else 2000
rng = np.random.default_rng(8)

# --- Your room ----------------------------------------------------------------------------
# Lengths are in the paper's units (a person is D = 3.33 across and walks 1 unit a step). The
# floor is a polygon; static occluders (the cupboard) block sight and cannot be walked through.
room = Room(rectangle(0, 80, 0, 50), static_occluders=(rectangle(30, 45, 20, 28),), name="mine")
diameter = 3.33

# Six cameras on the walls: positions, the direction each looks (degrees, anticlockwise from
# +x) and a 90 degree field of view. The noise parameters are the paper's (Sec. 3): angle error
# of the camera's pose (rad), position error of the camera, read-out noise of the image
# coordinate (pixels).
cameras = ring_of_cameras(
    [(0, 0), (40, 0), (80, 0), (80, 50), (40, 50), (0, 50)],
    [45, 90, 135, 225, 270, 315],
    90.0,
    sigma_theta=0.01,
    sigma_pos=1.0,
    sigma_read=2.0,
)

# --- The world: the person and six others, all random-waypoint walkers ---------------------
walkers = WaypointWalkers(room, speed=1.0, noise=0.33, diameter=diameter)
paths = walkers.trajectory(7, steps, rng)  # (steps + 1, 7 walkers, 2)
person, others = paths[:, 0], paths[:, 1:]

# What the cameras report: the image coordinate with noise where the person is in view, not
# behind the cupboard and not behind another walker (a disc of diameter D); NaN otherwise.
readings = np.full((steps + 1, len(cameras)), np.nan)
for t in range(steps + 1):
    x = person[t][None, None, :]
    seen = cameras.in_fov(x)[0] & ~room.sight_blocked(cameras.positions[None], x)[0]
    seen &= ~disks_block(cameras.positions, person[t], others[t], diameter)[:, 0]
    mean = cameras.image_coordinate(x)[0]
    sd = np.sqrt(cameras.noise_var(x)[0])
    readings[t, seen] = (mean + sd * rng.standard_normal(len(cameras)))[seen]
queried = np.array([0, 3])  # the cameras read each step: two opposite corners
hidden = np.mean(np.isnan(readings[1:, queried]))
print(f"{steps} steps, cameras {queried + 1} read: {100 * hidden:.0f}% of the readings 'not seen'")

# What the tracker may know of the others: their exact positions, or a Gaussian prior a few
# units off (here: the truth plus noise of standard deviation 3, and a matching covariance).
prior_sd = 3.0
noisy_means = others + prior_sd * rng.standard_normal(others.shape)


def knowledge(mode: str, t: int):
    if mode == "perfect":
        return others[t]
    if mode == "gaussian":
        covs = np.tile(prior_sd**2 * np.eye(2), (others.shape[1], 1, 1))
        return OccluderPriors(noisy_means[t], covs)
    return None


# --- Track with each level of knowledge ------------------------------------------------------
# Each step the queried cameras' readings (`selected`: their indices) and the occluder
# knowledge travel as one measurement value, a `CameraNetworkReport`. A small `floor` keeps a
# particle cloud that is slightly off from losing every weight (see the sensor's docstring).
errors = {}
for mode in ("perfect", "gaussian", "none"):
    likelihood = OcclusionAwareLikelihood(cameras, room, diameter, mode, floor=1e-3)
    tracker = WaypointASIR(
        room,
        WaypointRegimeDynamics(sigma_v=0.33),
        n_particles,
        sensors=(OcclusionAwareCameraSensor(likelihood),),
    )
    filter_rng = np.random.default_rng(9)
    belief = tracker.initialize(filter_rng)  # particles uniform over the free floor
    error = np.empty(steps)
    for t in range(1, steps + 1):
        report = CameraNetworkReport(readings[t, queried], queried, knowledge(mode, t))
        belief = tracker.step(belief, 1.0, [Measurement(float(t), "cameras", report)], filter_rng)
        error[t - 1] = np.hypot(*(belief.position - person[t]))
    errors[f"occluders: {mode}"] = error
    print(
        f"{mode:>9}: mean position error {error.mean():5.2f}, "
        f"last 20 steps {error[-20:].mean():5.2f}"
    )

args.out.mkdir(parents=True, exist_ok=True)
plot_series(
    args.out / "07_ercan_occlusion_own_room.png",
    np.arange(1, steps + 1),
    errors,
    xlabel="step",
    ylabel="position error (room units)",
    title="Your room: the occlusion-aware likelihood, three levels of knowledge",
    logy=True,
)
print(f"figure written to {args.out / '07_ercan_occlusion_own_room.png'}")
