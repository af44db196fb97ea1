"""Fusing a microphone array, a camera and a radio tag in one filter.

A person walks through a 100 m x 60 m yard, turning now and then. Three kinds of sensors watch:

* two **microphone arrays** in the bottom corners each report the *bearing* the sound comes
  from, every half second, within 3 degrees;
* a **camera** on the far wall reports a much sharper bearing (half a degree), but only inside
  its 70 degree field of view and not while the person is behind a shed;
* a **radio tag** the person carries is localised every 2 s, to within a couple of metres.

No sensor alone gives a good position: a bearing says nothing about distance, the tag is coarse
and slow. Together they pin the person down. We build the models, simulate a walk and the
reports, and fuse everything in an EKF, a UKF and a particle filter — the same sensor list goes
to all three. (The demo experiment, `fusetrack run demo`, is this scene with error bars.)

Run: `python docs/tutorials/02_fusing_sensors.py [--quick] [--out DIR]`.
"""

import argparse
import os
from pathlib import Path

import numpy as np

from fusetrack.core import Gaussian, Measurement
from fusetrack.evaluation import position_error
from fusetrack.evaluation.plots import plot_series
from fusetrack.filters import (
    BootstrapFilter,
    ExtendedKalmanFilter,
    UnscentedKalmanFilter,
    run_filter,
)
from fusetrack.motion import CoordinatedTurnRate
from fusetrack.sensors import Bearing, PositionFix


def options() -> argparse.Namespace:
    """`--quick` (or `FUSETRACK_QUICK=1`) for a short run; `--out DIR` for the figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", default=os.environ.get("FUSETRACK_QUICK") == "1"
    )
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "figures")
    return parser.parse_args()


args = options()
duration = 30.0 if args.quick else 60.0
n_particles = 500 if args.quick else 3000
dt = 0.5
rng = np.random.default_rng(3)

# --- The motion: a coordinated turn whose rate wanders ------------------------------------
# State [x, y, vx, vy, omega]: position (m), velocity (m/s) and turn rate (rad/s). The walker
# keeps its speed and turns at rate omega; q is the acceleration noise (m^2/s^3), q_omega lets
# the turn rate itself drift (rad^2/s^3).
motion = CoordinatedTurnRate(q=0.05, q_omega=2e-4)

# --- The sensors -------------------------------------------------------------------------------
# Bearings are anticlockwise from +x, relative to the sensor's heading; angles in radians.
mic_west = Bearing("mic_west", position=[0.0, 0.0], sigma=np.deg2rad(3.0))
mic_east = Bearing("mic_east", position=[100.0, 0.0], sigma=np.deg2rad(3.0))
camera = Bearing(
    "camera", position=[50.0, 62.0], sigma=np.deg2rad(0.5), heading=-np.pi / 2, fov=np.deg2rad(70.0)
)  # looking down (-y), 70 deg wide
tag = PositionFix("tag", cov=[[4.0, 1.2], [1.2, 2.25]])  # m^2, a tilted error ellipse
sensors = [mic_west, mic_east, camera, tag]

# The camera's field of view is part of its model: `simulate` returns NaN when the person is
# outside it. The shed is not: we say when it hides the person (seconds).
behind_shed = [(12.0, 18.0), (40.0, 46.0)]


def hidden(t: float) -> bool:
    return any(a <= t < b for a, b in behind_shed)


# --- Simulate the walk and the reports ----------------------------------------------------
# Each sensor reports on its own schedule; a report the sensor could not make is skipped. The
# filters take any mix of reports in time order.
prior = Gaussian(np.array([20.0, 20.0, 1.5, 0.8, 0.02]), np.diag([2.0, 2.0, 0.5, 0.5, 0.02]) ** 2)
x = prior.sample(rng)
times = dt * np.arange(1, round(duration / dt) + 1)
truth, reports = [], []
for t in times:
    x = motion.sample(x, dt, rng)
    truth.append(x)
    for sensor in sensors:
        if sensor is tag and not np.isclose(t % 2.0, 0.0):
            continue  # the tag every 2 s
        if sensor is camera and hidden(t):
            continue  # the shed
        z = sensor.simulate(x, rng)
        if np.all(np.isfinite(z)):  # NaN: outside the camera's field of view
            reports.append(Measurement(float(t), sensor.sensor_id, z))
truth = np.array(truth)
counts = {s.sensor_id: sum(m.sensor_id == s.sensor_id for m in reports) for s in sensors}
print(f"{len(times)} steps, reports per sensor: {counts}")

# --- Three filters, one sensor list --------------------------------------------------------
# The EKF linearises the bearings at the prediction, the UKF pushes sigma points through them,
# the particle filter weighs samples by every sensor's likelihood. `times=` asks for an
# estimate at every step (so every filter is compared at the same times) and `t0=0` is the
# prior's time. The particle filter draws random numbers: give it a generator.
filters = {
    "EKF": ExtendedKalmanFilter(motion, sensors),
    "UKF": UnscentedKalmanFilter(motion, sensors),
    f"PF ({n_particles} particles)": BootstrapFilter(
        motion, sensors, n_particles=n_particles, ess_threshold=0.5
    ),
}
errors = {}
for name, filt in filters.items():
    track = run_filter(filt, prior, reports, times=times, t0=0.0, rng=np.random.default_rng(1))
    errors[name] = position_error(track.means, truth, [0, 1])
    print(f"{name:>22}: mean position error {errors[name].mean():.2f} m")

# What does each sensor bring? Run the EKF again without the camera, and with the tag alone.
for label, keep in (
    ("EKF without the camera", {"mic_west", "mic_east", "tag"}),
    ("EKF, tag alone", {"tag"}),
):
    subset = [m for m in reports if m.sensor_id in keep]
    track = run_filter(ExtendedKalmanFilter(motion, sensors), prior, subset, times=times, t0=0.0)
    errors[label] = position_error(track.means, truth, [0, 1])
    print(f"{label:>22}: mean position error {errors[label].mean():.2f} m")

# --- The figure: error against time, the shed's stretches shaded -----------------------------
args.out.mkdir(parents=True, exist_ok=True)
plot_series(
    args.out / "02_fusing_sensors.png",
    times,
    errors,
    xlabel="time (s)",
    ylabel="position error (m)",
    title="Microphones + camera + tag, fused",
    logy=True,
    shade=[(a, min(b, duration)) for a, b in behind_shed if a < duration],
    shade_label="camera: person behind the shed",
)
print(f"figure written to {args.out / '02_fusing_sensors.png'}")
