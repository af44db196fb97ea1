"""Parameter estimation: fit a noise level by maximising the filter's log-likelihood.

A Kalman filter needs its noise levels: how much the target's velocity wanders (the process
noise `q`) and how noisy the sensor is. Often neither is known. But the filter itself tells us
how well a setting explains the data: each update's *innovation* ``z - H x_pred`` is Gaussian
with covariance ``S = H P_pred H^T + R``, so the filter gives the likelihood of the whole
recording, ``log p(z_1:T | theta) = sum_k log N(z_k; H x_pred, S_k)`` (the prediction error
decomposition; Harvey 1989, Sec. 3.4; Särkkä 2013, Sec. 12.3). Maximising it over ``theta``
is maximum-likelihood estimation.

In fusetrack every filter that can report it is a `LikelihoodFilter` (`update_with_likelihood`
returns the belief and ``log p(z_k | z_1:k-1)``), and `run_filter(..., log_likelihood=True)` sums
the increments into ``track.info["log_likelihood"]``. We

1. simulate a target whose true process noise we pretend not to know, seen by a position sensor
   of unknown noise,
2. write the negative log-likelihood of ``(log q, log sigma)`` with `run_filter`,
3. minimise it with `scipy.optimize.minimize` and get standard errors from the curvature,
4. plot the profile of the log-likelihood over ``q``.

(The same log-likelihood works for particle filters, where it is a noisy estimate: that is the
road to particle marginal Metropolis–Hastings.)

Run: `python docs/tutorials/05_fit_noise_by_likelihood.py [--quick] [--out DIR]`.
"""

import argparse
import os
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from fusetrack.core import Gaussian, Measurement
from fusetrack.evaluation.plots import plot_series
from fusetrack.filters import KalmanFilter, run_filter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix


def options() -> argparse.Namespace:
    """`--quick` (or `FUSETRACK_QUICK=1`) for a short run; `--out DIR` for the figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", default=os.environ.get("FUSETRACK_QUICK") == "1"
    )
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "figures")
    return parser.parse_args()


args = options()
steps = 100 if args.quick else 600
true_q, true_sigma = 0.3, 0.8  # m^2/s^3 and m
rng = np.random.default_rng(2)

# --- 1. A recording --------------------------------------------------------------------------
truth_motion = ConstantVelocity(ndim=2, q=true_q)
truth_sensor = PositionFix("gps", cov=true_sigma**2 * np.eye(2))
x = np.array([0.0, 0.0, 1.0, 0.5])
reports = []
for k in range(1, steps + 1):
    x = truth_motion.sample(x, 1.0, rng)
    reports.append(Measurement(float(k), "gps", truth_sensor.simulate(x, rng)))

# --- 2. The negative log-likelihood of a setting ------------------------------------------------
# We optimise over logarithms: both parameters are positive, and the likelihood is closer to
# quadratic in the logs. A vague prior at the first fix keeps the start from mattering much.
prior = Gaussian(np.array([*reports[0].value, 0.0, 0.0]), np.diag([25.0, 25.0, 25.0, 25.0]))


def negative_log_likelihood(theta: np.ndarray) -> float:
    q, sigma = np.exp(theta)
    kf = KalmanFilter(ConstantVelocity(ndim=2, q=q), [PositionFix("gps", cov=sigma**2 * np.eye(2))])
    track = run_filter(kf, prior, reports, t0=0.0, log_likelihood=True)
    return -float(track.info["log_likelihood"])


# --- 3. Maximum likelihood with scipy -----------------------------------------------------------
start = np.log([1.0, 2.0])  # a deliberately poor first guess
fit = minimize(negative_log_likelihood, start, method="L-BFGS-B")
q_hat, sigma_hat = np.exp(fit.x)

# Standard errors from the curvature: the inverse Hessian of the negative log-likelihood (in the
# logs) is the asymptotic covariance; a central finite difference is enough here.
h = 1e-3
hessian = np.empty((2, 2))
for i in range(2):
    for j in range(2):
        ei, ej = np.eye(2)[i] * h, np.eye(2)[j] * h
        hessian[i, j] = (
            negative_log_likelihood(fit.x + ei + ej)
            - negative_log_likelihood(fit.x + ei - ej)
            - negative_log_likelihood(fit.x - ei + ej)
            + negative_log_likelihood(fit.x - ei - ej)
        ) / (4 * h * h)
se = np.sqrt(np.diag(np.linalg.inv(hessian)))  # of log q and log sigma
print(f"{steps} reports, {fit.nfev} filter runs")
for name, true, fitted, s in (("q", true_q, q_hat, se[0]), ("sigma", true_sigma, sigma_hat, se[1])):
    low, high = fitted * np.exp(-1.96 * s), fitted * np.exp(1.96 * s)
    print(f"{name:>5}: true {true}, fitted {fitted:.3f} (95% interval {low:.3f} to {high:.3f})")

# --- 4. The profile over q (sigma at its fitted value) -----------------------------------------
grid = np.linspace(np.log(0.05), np.log(2.0), 9 if args.quick else 40)
profile = np.array([-negative_log_likelihood(np.array([g, fit.x[1]])) for g in grid])
args.out.mkdir(parents=True, exist_ok=True)
plot_series(
    args.out / "05_fit_noise_by_likelihood.png",
    np.exp(grid),
    {
        "log-likelihood (sigma at its fit)": profile - profile.max(),
        "95% cut-off (-1.92)": np.full(grid.size, -1.92),
    },
    xlabel="process noise q (m²/s³)",
    ylabel="log-likelihood − its maximum",
    title=f"Fitting q: true {true_q}, fitted {q_hat:.2f}",
    styles={"95% cut-off (-1.92)": "k:"},
)
print(f"figure written to {args.out / '05_fit_noise_by_likelihood.png'}")
