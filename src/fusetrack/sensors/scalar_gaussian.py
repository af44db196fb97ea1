"""The part shared by scalar sensors ``z = h(x) + v``, ``v ~ N(0, sigma^2)``, seen always.

Zhai 2007's power-law sensor (Eqs. 32, 94) and received acoustic intensity (Eq. 37) differ only
in ``h`` and its Jacobian; their residual, Gaussian log-likelihood, simulation, Fisher information
``H^T H / sigma^2`` and detection probability (one) live here, once. A subclass (a frozen
dataclass) supplies ``predict(x) -> (..., 1)``, ``jacobian(x) -> (..., 1, d)`` and the noise
standard deviation as the property ``noise_sd``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

Array = np.ndarray


class ScalarGaussianSensor:
    """Mixin: one non-angular component with constant Gaussian noise ``N(0, noise_sd^2)``."""

    @property
    def noise_sd(self) -> float:
        """The standard deviation of ``v``."""
        raise NotImplementedError

    def predict(self, x: ArrayLike) -> Array:
        """``h(x)``, shape ``(..., 1)``."""
        raise NotImplementedError

    def jacobian(self, x: ArrayLike) -> Array:
        """``dh/dx``, shape ``(..., 1, d)``."""
        raise NotImplementedError

    @property
    def dim(self) -> int:
        return 1

    @property
    def angular(self) -> tuple[bool, ...]:
        return (False,)

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> Array:
        return np.asarray(np.subtract(z, z_pred), dtype=float)

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        return np.array([[self.noise_sd**2]])

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> Array:
        """``log N(z; h(x), sigma^2)``; a diverged state (inf) gives -inf or NaN, silently."""
        sd = self.noise_sd
        r = self.residual(z, self.predict(x))[..., 0] / sd
        with np.errstate(over="ignore", invalid="ignore"):
            return np.asarray(-0.5 * r * r - math.log(sd) - 0.5 * math.log(2 * math.pi))

    def simulate(self, x: ArrayLike, rng: np.random.Generator) -> Array:
        """``h(x) + v``: one ``standard_normal`` draw per measurement."""
        z = self.predict(x)
        return np.asarray(z + self.noise_sd * rng.standard_normal(z.shape))

    def fisher_information(self, x: ArrayLike) -> Array:
        """``H^T H / sigma^2``, shape ``(..., d, d)``."""
        H = self.jacobian(x)
        return np.asarray(np.swapaxes(H, -1, -2) @ H / self.noise_sd**2)

    def detection_probability(self, x: ArrayLike) -> Array:
        return np.ones(np.asarray(x).shape[:-1])
