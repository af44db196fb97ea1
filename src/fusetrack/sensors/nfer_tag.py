"""A simulated near-field electromagnetic ranging (NFER) radio tag, and fitting its noise model.

Nott (2009) used a Q-Track QT-400 kit: after the vendor's calibration it reports the tag's floor
position directly (a :class:`~fusetrack.sensors.PositionFix` in the filter, Nott 2009, Eq. 3.10).
Its errors in Table 5.1 are not white: the x error dominates, nearby points share errors and
the outputs repeat exact values (7.013 three times), as if snapped to a grid of about 0.1 m.
:class:`NferTagSimulator` draws reports with a choice of error model:

* ``"white"``: i.i.d. Gaussian, standard deviations ``sigma`` (the thesis's simulation, Sec. 5.1:
  0.6 m and 0.4 m);
* ``"field"``: a smooth spatially correlated bias (a Gaussian random field with squared-exponential
  correlation of length ``corr_length``, per-axis standard deviations ``bias_std``, fixed for one
  building = one ``field_seed``), plus white noise ``sigma``, then quantised to ``quantum`` metres;

and optional dropouts (probability ``dropout`` per report) and a clock offset (applied by the
caller to the timestamps). :func:`fit_position_fix` estimates the noise from calibration points
(Nott 2009, Sec. 4.6, corrected: the thesis averages the residuals, which measures a bias; the
covariance is their sample covariance).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, ShapeError, check_positive, check_probability, invalid
from .camera_geometry import Array
from .position_fix import PositionFix

_N_FEATURES = 256


@dataclass(frozen=True, eq=False)
class NferTagSimulator:
    """Draws radio-tag position reports ``z = p + error`` (see the module docstring)."""

    model: Literal["white", "field"] = "white"
    sigma: tuple[float, float] = (0.6, 0.4)
    bias_std: tuple[float, float] = (0.50, 0.17)
    corr_length: float = 2.0
    quantum: float = 0.0
    dropout: float = 0.0
    field_seed: int = 2009

    _omega: Array = field(init=False, repr=False)
    _phase: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.model not in ("white", "field"):
            raise ConfigError(invalid("model", self.model, "'white' or 'field'"))
        for name in ("sigma", "bias_std"):
            v = np.asarray(getattr(self, name), float)
            if v.shape != (2,) or not np.all(np.isfinite(v)) or np.any(v < 0):
                raise ConfigError(invalid(name, getattr(self, name), "two finite numbers >= 0 (m)"))
        check_positive("corr_length", self.corr_length)
        check_positive("quantum", self.quantum, allow_zero=True)
        check_probability("dropout", self.dropout)
        g = np.random.default_rng(self.field_seed)
        # random Fourier features of the squared-exponential kernel exp(-|d|^2 / (2 l^2))
        object.__setattr__(
            self, "_omega", g.standard_normal((2, _N_FEATURES, 2)) / self.corr_length
        )
        object.__setattr__(self, "_phase", g.uniform(0, 2 * np.pi, (2, _N_FEATURES)))

    def bias(self, p: ArrayLike) -> Array:
        """The position-dependent bias ``(..., 2)`` (zero for the white model)."""
        pa = np.asarray(p, float)
        if self.model == "white":
            return np.zeros_like(pa)
        out = []
        for axis in range(2):
            arg = pa @ self._omega[axis].T + self._phase[axis]
            out.append(np.sqrt(2.0 / _N_FEATURES) * np.cos(arg).sum(-1) * self.bias_std[axis])
        return np.stack(out, axis=-1)

    def simulate(self, p: ArrayLike, rng: np.random.Generator) -> Array:
        """Reports ``(..., 2)`` for true floor positions ``p`` ``(..., 2)``; NaN rows are dropouts."""
        pa = np.asarray(p, float)
        if pa.ndim == 0 or pa.shape[-1] != 2:
            raise ShapeError(invalid("p.shape", pa.shape, "(..., 2) floor positions (m)"))
        z = pa + self.bias(pa) + rng.standard_normal(pa.shape) * np.asarray(self.sigma)
        if self.quantum > 0:
            z = np.round(z / self.quantum) * self.quantum
        lost = rng.random(pa.shape[:-1]) < self.dropout
        z[lost] = np.nan
        return z

    def position_fix(self, sensor_id: str = "tag") -> PositionFix:
        """The filter's model of this tag: white noise with the simulator's total variance."""
        var = np.asarray(self.sigma, float) ** 2 + self.quantum**2 / 12.0
        if self.model == "field":
            var = var + np.asarray(self.bias_std, float) ** 2
        return PositionFix(sensor_id, cov=np.diag(var), position_index=(0, 1))


@dataclass(frozen=True)
class TagNoiseFit:
    """Residual statistics at calibration points: ``bias`` (mean), ``cov`` (sample covariance),
    and the Euclidean errors' mean and sample standard deviation."""

    bias: Array
    cov: Array
    mean_error: float
    std_error: float
    n: int


def fit_position_fix(truth: ArrayLike, measured: ArrayLike) -> TagNoiseFit:
    """Noise statistics of a position sensor from calibration points (Nott 2009, Sec. 4.6 / 3.15).

    ``truth`` and ``measured`` are ``(n, 2)``; residuals ``e = measured - truth``. The thesis
    "averaged" the residuals (that is the ``bias``); the covariance the filter needs is
    ``cov(e)`` (``ddof = 1``).
    """
    t = np.asarray(truth, float)
    m = np.asarray(measured, float)
    if t.shape != m.shape or t.ndim != 2 or t.shape[1] != 2 or t.shape[0] < 2:
        raise ShapeError(
            invalid("(truth, measured) shapes", (t.shape, m.shape), "two equal (n, 2), n >= 2")
        )
    e = m - t
    err = np.linalg.norm(e, axis=1)
    return TagNoiseFit(
        e.mean(0), np.cov(e.T, ddof=1), float(err.mean()), float(err.std(ddof=1)), len(e)
    )


__all__ = ["NferTagSimulator", "TagNoiseFit", "fit_position_fix"]
