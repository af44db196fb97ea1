"""Several targets: trackers, association, clutter and GOSPA.

A surveillance sensor over a 100 m x 100 m square reports position *plots*: each target is
detected with probability 0.9 per scan, and every scan also brings a few false alarms
(clutter) scattered over the square. Targets come and go. The sensor does not say which plot
belongs to which target — that is the tracker's job:

* **MultiTargetTracker** is assembled from parts: a Kalman filter per track, an *associator*
  that decides which plot updates which track (global nearest neighbour, GNN, or joint
  probabilistic data association, JPDA), an *initiator* that starts tentative tracks from
  unused plots and confirms those seen in M of their first N scans, and a *deleter* that ends
  tracks missed too many times in a row;
* **PMBTracker** (the Poisson multi-Bernoulli filter of Williams 2015) takes a different view:
  undetected targets are a Poisson intensity, detected ones Bernoulli components with an
  existence probability; births come from a birth intensity over the square.

All of them have one interface — `state = tracker.step(state, time, plots, rng)`, with the
confirmed tracks in `state.confirmed` — so one loop runs them all. We score them with GOSPA
(Rahmathullah, García-Fernández & Svensson 2017), which adds localisation error, missed
targets and false tracks into one distance per scan.

Run: `python docs/tutorials/04_several_targets.py [--quick] [--out DIR]`.
"""

import argparse
import os
from pathlib import Path

import numpy as np

from fusetrack.association import GlobalNearestNeighbour, JointProbabilisticDataAssociation
from fusetrack.core import Gaussian, Measurement
from fusetrack.evaluation import gospa_over_time
from fusetrack.evaluation.plots import plot_series
from fusetrack.filters import KalmanFilter, PhdIntensity
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix
from fusetrack.tracking import (
    InverseMeasurementPrior,
    MissedCountDeleter,
    MofNInitiator,
    MultiTargetTracker,
    PMBFilter,
    PMBTracker,
)


def options() -> argparse.Namespace:
    """`--quick` (or `FUSETRACK_QUICK=1`) for a short run; `--out DIR` for the figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", default=os.environ.get("FUSETRACK_QUICK") == "1"
    )
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "figures")
    return parser.parse_args()


args = options()
scans = 40 if args.quick else 80  # one scan a second
area = 100.0 * 100.0  # m^2
clutter_per_scan = 3.0 if args.quick else 5.0
p_detect = 0.9
rng = np.random.default_rng(5)

# --- The world: targets that come and go ------------------------------------------------
# (start scan, end scan, initial state [x, y, vx, vy]); end scans are clipped to the run.
motion = ConstantVelocity(ndim=2, q=0.05)
targets = [
    (0, 60, [10.0, 10.0, 1.2, 1.0]),
    (0, 80, [10.0, 90.0, 1.2, -1.0]),  # crosses the first one around scan 40
    (10, 80, [90.0, 50.0, -1.0, 0.1]),
    (25, 70, [50.0, 5.0, 0.0, 1.1]),
]
sensor = PositionFix("plots", cov=np.eye(2))  # 1 m standard deviation per axis

truth_sets, scans_of_plots = [], []
states = {k: np.array(x0) for k, (_, _, x0) in enumerate(targets)}
for t in range(scans):
    alive, plots = [], []
    for k, (start, end, _) in enumerate(targets):
        if start <= t < end:
            if t > start:
                states[k] = motion.sample(states[k], 1.0, rng)
            alive.append(states[k][:2])
            if rng.random() < p_detect:
                plots.append(sensor.simulate(states[k], rng))
    # clutter: a Poisson number of false alarms, uniform over the square
    plots += list(rng.uniform(0.0, 100.0, size=(rng.poisson(clutter_per_scan), 2)))
    rng.shuffle(plots)
    truth_sets.append(np.array(alive).reshape(-1, 2))
    scans_of_plots.append([Measurement(float(t), "plots", z) for z in plots])

# --- The trackers ---------------------------------------------------------------------------
kf = KalmanFilter(motion, [sensor])
clutter_density = clutter_per_scan / area  # false alarms per m^2 per scan
# A new track starts at the plot, with the velocity unknown (0 +- 2 m/s).
new_track = InverseMeasurementPrior([sensor], Gaussian(np.zeros(4), np.diag([0, 0, 4.0, 4.0])))


def scan_tracker(associator, m, n):
    return MultiTargetTracker(
        kf,
        [sensor],
        associator,
        initiator=MofNInitiator(m, n, new_track),  # confirmed when seen in m of its first n scans
        deleter=MissedCountDeleter(3),  # ended after 3 misses in a row
        p_detect=p_detect,
        clutter_density=clutter_density,
    )


# The PMB filter's birth intensity: where new targets may appear, and how many per scan (here
# 0.05 spread over a 4 x 4 grid of Gaussians that covers the square).
cells = 4
centres = (np.arange(cells) + 0.5) * 100.0 / cells
gx, gy = np.meshgrid(centres, centres)
birth = PhdIntensity(
    np.full(cells * cells, 0.05 / cells**2),
    np.column_stack([gx.ravel(), gy.ravel(), np.zeros((cells * cells, 2))]),
    np.tile(np.diag([(100.0 / cells) ** 2] * 2 + [4.0, 4.0]), (cells * cells, 1, 1)),
)
pmb = PMBFilter(
    motion,
    [sensor],
    birth,
    survival_probability=0.99,
    detection_probability=p_detect,
    clutter_intensity=clutter_density,
)

trackers = {
    "GNN, 3 of 4": scan_tracker(GlobalNearestNeighbour(), 3, 4),
    "GNN, 4 of 5": scan_tracker(GlobalNearestNeighbour(), 4, 5),
    "JPDA, 4 of 5": scan_tracker(JointProbabilisticDataAssociation(), 4, 5),
    "PMB": PMBTracker(pmb, threshold=0.5),
}

# Which confirmation rule? Each scan brings a few false alarms, and a tentative track started
# by one has a wide gate (its velocity is unknown) where the next false alarm may fall. At
# full size (5 false alarms a scan) "3 of 4" confirmed several such ghosts and "4 of 5" almost
# none, at the price of confirming real targets one scan later: see the printed counts.

# --- One loop for every tracker ------------------------------------------------------------
# Every sensor is taken to have looked at every scan, so a scan that brought no plot at all is
# a miss for every track; `scanned=[...]` names the sensors that looked when some did not.
estimates = {name: [] for name in trackers}
ids_seen = {name: set() for name in trackers}
for name, tracker in trackers.items():
    state = tracker.initial_state()
    tracker_rng = np.random.default_rng(0)
    for t, plots in enumerate(scans_of_plots):
        state = tracker.step(state, float(t), plots, tracker_rng)
        confirmed = state.confirmed
        estimates[name].append(np.array([tr.belief.mean[:2] for tr in confirmed]).reshape(-1, 2))
        ids_seen[name] |= {tr.id for tr in confirmed}

# --- GOSPA: one number per scan ------------------------------------------------------------
# With cut-off c = 10 m, a track farther than c from any target counts as a false track
# (c^2 / 2) and the target as missed (c^2 / 2); p = 2 makes the localisation part a sum of
# squared errors.
gospa = {name: gospa_over_time(est, truth_sets, c=10.0, p=2.0) for name, est in estimates.items()}
print(f"{scans} scans, {len(targets)} targets, {clutter_per_scan} false alarms per scan")
for name, g in gospa.items():
    print(
        f"  {name:>12}: mean GOSPA {g.distance.mean():5.2f} m, "
        f"missed {g.n_missed.sum():3d}, false {g.n_false.sum():3d} (target-scans), "
        f"{len(ids_seen[name])} track ids"
    )

args.out.mkdir(parents=True, exist_ok=True)
plot_series(
    args.out / "04_several_targets.png",
    np.arange(scans),
    {name: g.distance for name, g in gospa.items()},
    xlabel="time (s)",
    ylabel="GOSPA (m), c = 10 m",
    title=f"{len(targets)} targets, {clutter_per_scan:g} false alarms a scan, P_D = {p_detect}",
)
print(f"figure written to {args.out / '04_several_targets.png'}")
