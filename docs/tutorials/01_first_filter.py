"""A first filter: one target, one sensor, a Kalman filter.

A target crosses a 100 m field at walking-to-cycling speed, moving as a *nearly constant
velocity* model says: straight on, its velocity nudged by white-noise acceleration. A radio tag
reports its position once a second with half a metre of noise. We

1. write down the motion model and the sensor model,
2. simulate a true path and the tag's reports,
3. run a Kalman filter over the reports with `run_filter` and compare it with the truth,
4. swap the tag for a radar that reports *range and bearing* — a nonlinear sensor — and run an
   extended Kalman filter (EKF) on the same path.

Run it with `python docs/tutorials/01_first_filter.py` (add `--quick` for a short run); the
figure goes to `docs/tutorials/figures/01_first_filter.png` (or `--out DIR`).
"""

import argparse
import os
from pathlib import Path

import numpy as np

from fusetrack.core import Gaussian, Measurement
from fusetrack.evaluation import nees, position_error
from fusetrack.evaluation.plots import plot_trajectories
from fusetrack.filters import ExtendedKalmanFilter, KalmanFilter, run_filter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix, RangeBearing


def options() -> argparse.Namespace:
    """`--quick` (or `FUSETRACK_QUICK=1`) for a short run; `--out DIR` for the figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", default=os.environ.get("FUSETRACK_QUICK") == "1"
    )
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "figures")
    return parser.parse_args()


args = options()
steps = 30 if args.quick else 90  # one report per second
rng = np.random.default_rng(7)

# --- 1. The models ------------------------------------------------------------------------
# The state is [x, y, vx, vy] (metres, metres per second): positions first, then velocities.
# `q` is the power spectral density of the white-noise acceleration (m^2/s^3): how much the
# velocity may wander per second.
motion = ConstantVelocity(ndim=2, q=0.01)

# The tag reports the position [x, y] with covariance `cov` (m^2). Every sensor has an id; a
# measurement names the sensor it came from, and the filter routes it to that model.
tag = PositionFix("tag", cov=0.25 * np.eye(2))

# --- 2. A true path and the tag's reports --------------------------------------------------
# Every model can simulate itself: `motion.sample` draws the next state, `sensor.simulate` a
# noisy report. A `Measurement` is (time, sensor id, value).
x = np.array([5.0, 10.0, 1.2, 0.4])
truth, reports = [], []
for k in range(1, steps + 1):
    x = motion.sample(x, 1.0, rng)
    truth.append(x)
    reports.append(Measurement(float(k), "tag", tag.simulate(x, rng)))
truth = np.array(truth)

# --- 3. A Kalman filter ----------------------------------------------------------------------
# A filter is a motion model and a list of sensors; it holds no state of its own. The belief it
# carries from step to step is a Gaussian: we start at time 0 from a vague one around where the
# target was first seen (position within ~3 m, speed within ~2 m/s; a prior centred on the
# radar itself would be a poor place to linearise its bearing, step 4). `run_filter` predicts to
# each report's time, updates with it and returns a `Track`: times, means (T, 4) and
# covariances (T, 4, 4).
first_seen = reports[0].value
prior = Gaussian(np.array([*first_seen, 0.0, 0.0]), np.diag([9.0, 9.0, 4.0, 4.0]))
kf = KalmanFilter(motion, [tag])
track_kf = run_filter(kf, prior, reports, t0=0.0)

err_kf = position_error(track_kf.means, truth, [0, 1])
err_tag = np.linalg.norm([m.value for m in reports] - truth[:, :2], axis=1)
print(
    f"Kalman filter: mean position error {err_kf.mean():.2f} m "
    f"(the tag alone: {err_tag.mean():.2f} m)"
)

# The filter also says how sure it is: the covariance. If it is honest, the squared error
# normalised by it (NEES) averages the state dimension, here 2 for the position.
# (The first few steps, still dominated by the prior, are left out.)
position_nees = nees(track_kf.means, track_kf.covariances, truth, index=[0, 1])
print(f"position NEES averages {position_nees[5:].mean():.2f} (2 for a consistent filter)")

# --- 4. A nonlinear sensor and an EKF ---------------------------------------------------------
# A radar at the origin reports range (sigma 0.5 m) and bearing (sigma 1 degree). The bearing
# is an angle: the sensor model wraps its residuals to [-pi, pi), so the filters never see a
# jump of 2 pi. The Kalman filter needs a linear sensor; the EKF linearises h(x) at the
# prediction with the sensor's Jacobian.
radar = RangeBearing("radar", position=[0.0, 0.0], sigma_range=0.5, sigma_bearing=np.deg2rad(1.0))
radar_reports = [
    Measurement(float(k), "radar", radar.simulate(x, rng)) for k, x in enumerate(truth, start=1)
]
ekf = ExtendedKalmanFilter(motion, [radar])
track_ekf = run_filter(ekf, prior, radar_reports, t0=0.0)
err_ekf = position_error(track_ekf.means, truth, [0, 1])
print(f"EKF on the radar: mean position error {err_ekf.mean():.2f} m")

# Both sensors at once is just a longer list: the filter takes any mix of reports, in time
# order, and fuses those that share a time step one after the other.
both = ExtendedKalmanFilter(motion, [tag, radar])
track_both = run_filter(both, prior, sorted(reports + radar_reports, key=lambda m: m.time), t0=0.0)
err_both = position_error(track_both.means, truth, [0, 1])
print(f"EKF on tag + radar: mean position error {err_both.mean():.2f} m")

# --- The figure ------------------------------------------------------------------------------
# `plot_trajectories` draws the truth and each estimate with its own colour, line style and
# markers, so estimates that lie on top of each other stay visible.
args.out.mkdir(parents=True, exist_ok=True)
plot_trajectories(
    args.out / "01_first_filter.png",
    truth,
    {
        "Kalman filter (tag)": track_kf.means,
        "EKF (radar)": track_ekf.means,
        "EKF (tag + radar)": track_both.means,
    },
    sensors=[("radar", radar.position)],
    title="A first filter: truth and estimates",
)
print(f"figure written to {args.out / '01_first_filter.png'}")
