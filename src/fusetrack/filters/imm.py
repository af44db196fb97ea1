r"""The interacting multiple model (IMM) filter over fusetrack's Gaussian filters.

A bank of ``M`` Gaussian filters (EKF by default; KF or UKF work the same), one per motion model,
whose regimes follow a Markov chain with row-stochastic ``transition[i, j] = P(r_t = j | r_{t-1} = i)``
(Blom & Bar-Shalom 1988; Bar-Shalom, Li & Kirubarajan 2001, Sec. 11.6.6). One cycle:

1. **Mixing** (:func:`imm_mix`): predicted regime probabilities ``c_j = sum_i p_ij mu_i``, mixing
   weights ``mu_{i|j} = p_ij mu_i / c_j``, and per model the mixed initial condition
   ``x0_j = sum_i mu_{i|j} x_i``, ``P0_j = sum_i mu_{i|j} [P_i + (x_i - x0_j)(x_i - x0_j)^T]``.
2. **Model-conditioned prediction**: filter ``j`` predicts ``N(x0_j, P0_j)`` with model ``j``.
3. **Model-conditioned update** with the likelihood ``Lambda_j = N(z; z^_j, S_j)``
   (:meth:`GaussianFilter.update_with_likelihood`), and ``mu_j ∝ Lambda_j c_j`` (log domain).
4. **Output** the moment-matched Gaussian ``x = sum_j mu_j x_j``,
   ``P = sum_j mu_j [P_j + (x_j - x)(x_j - x)^T]`` (:meth:`IMMBelief.combined`).

:meth:`InteractingMultipleModel.predict` does steps 1-2 (the belief then carries the predicted
probabilities ``c``), :meth:`~InteractingMultipleModel.update` steps 3. With one model the IMM is
exactly its Gaussian filter. Every model must share the state layout (pad 4-D models into a
6-D constant-acceleration state with :class:`~fusetrack.filters.multiple_model.PaddedModel`).
Beliefs may carry leading batch axes (independent runs), as the Gaussian filters do.

>>> import numpy as np
>>> from fusetrack.core import Gaussian, Measurement
>>> from fusetrack.motion import ConstantVelocity
>>> from fusetrack.motion.maneuver import ManeuverTurn
>>> from fusetrack.sensors import PositionFix
>>> imm = InteractingMultipleModel(
...     [ConstantVelocity(q=0.01), ManeuverTurn(0.5, 1, 0.01)],
...     [[0.9, 0.1], [0.1, 0.9]],
...     [PositionFix("gps", cov=np.eye(2))],
... )
>>> b = imm.initialize(Gaussian(np.array([0.0, 0.0, 1.0, 0.0]), np.eye(4)))
>>> b = imm.update(imm.predict(b, 1.0), [Measurement(1.0, "gps", [1.0, 0.0])])
>>> b.probs.round(3).tolist(), b.combined().mean.shape
([0.504, 0.496], (4,))
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import logsumexp

from ..core import ConfigError, Gaussian, Measurement, MotionModel, ShapeError, invalid
from .kalman import Array, ExtendedKalmanFilter, GaussianFilter, Sensors
from .multiple_model import check_initial_probs, check_transition
from .stats import FilterStats


@dataclass(frozen=True, eq=False)
class IMMBelief:
    """Model-conditioned Gaussians and regime probabilities.

    ``means`` ``(..., M, d)``, ``covs`` ``(..., M, d, d)``, ``probs`` ``(..., M)`` (posterior after
    an update, predicted ``c_j`` after a predict).
    """

    means: Array
    covs: Array
    probs: Array

    def combined(self) -> Gaussian:
        """The moment-matched Gaussian of the mixture (Bar-Shalom et al. 2001, Eq. 11.6.6-20/21)."""
        return Gaussian(*_moment_match(self.means, self.covs, self.probs))

    @property
    def mean(self) -> Array:
        """``sum_j mu_j x_j`` ``(..., d)``: the IMM's output estimate."""
        return np.asarray(np.einsum("...k,...kd->...d", self.probs, self.means))

    @property
    def cov(self) -> Array:
        """The moment-matched covariance ``(..., d, d)``."""
        return _moment_match(self.means, self.covs, self.probs)[1]


def _moment_match(means: Array, covs: Array, w: Array) -> tuple[Array, Array]:
    """``sum_k w_k x_k`` and ``sum_k w_k [P_k + dev_k dev_k^T]`` over the model axis ``-2``/``-3``."""
    mean = np.einsum("...k,...kd->...d", w, means)
    dev = means - mean[..., None, :]
    cov = np.einsum("...k,...kij->...ij", w, covs) + np.einsum(
        "...k,...ki,...kj->...ij", w, dev, dev
    )
    return mean, 0.5 * (cov + np.swapaxes(cov, -1, -2))


def imm_mix(
    means: Array, covs: Array, probs: Array, transition: Array
) -> tuple[Array, Array, Array]:
    """IMM interaction step: ``(x0 (..., M, d), P0 (..., M, d, d), c (..., M))``.

    ``c_j = sum_i p_ij mu_i``; ``mu_{i|j} = p_ij mu_i / c_j`` (a model no regime can reach,
    ``c_j = 0``, keeps its own estimate); ``x0_j``, ``P0_j`` moment-match the mixture
    ``sum_i mu_{i|j} N(x_i, P_i)`` (Bar-Shalom et al. 2001, Eqs. 11.6.6-7 to 11.6.6-11).
    """
    joint = probs[..., :, None] * transition  # (..., i, j) = p_ij mu_i
    c = joint.sum(axis=-2)
    m = means.shape[-2]
    own = np.broadcast_to(np.eye(m), joint.shape)
    cond = np.where(c[..., None, :] > 0, joint / np.where(c > 0, c, 1.0)[..., None, :], own)
    w = np.swapaxes(cond, -1, -2)  # (..., j, i) = mu_{i|j}
    x0 = np.einsum("...ji,...id->...jd", w, means)
    dev = means[..., None, :, :] - x0[..., :, None, :]  # (..., j, i, d)
    p0 = np.einsum("...ji,...iab->...jab", w, covs) + np.einsum(
        "...ji,...jia,...jib->...jab", w, dev, dev
    )
    return x0, 0.5 * (p0 + np.swapaxes(p0, -1, -2)), c


class InteractingMultipleModel:
    """IMM filter: one ``filter_cls`` (default :class:`ExtendedKalmanFilter`) per motion model.

    Parameters
    ----------
    models:
        the motion models, all with the same state dimension.
    transition:
        ``(M, M)`` row-stochastic regime transition matrix.
    sensors:
        as for the Gaussian filters (a mapping or a sequence of sensor models).
    filter_cls:
        a :class:`GaussianFilter` subclass taking ``(motion, sensors)``.
    initial_probs:
        regime probabilities of :meth:`initialize` (default uniform).
    """

    def __init__(
        self,
        models: Sequence[MotionModel],
        transition: ArrayLike,
        sensors: Sensors,
        filter_cls: type[GaussianFilter] = ExtendedKalmanFilter,
        initial_probs: ArrayLike | None = None,
    ) -> None:
        if len(models) < 1:
            raise ConfigError(invalid("models", len(models), "at least one motion model"))
        dims = {int(m.dim) for m in models}
        if len(dims) != 1:
            raise ConfigError(invalid("models[].dim", sorted(dims), "one common state dimension"))
        self.models = tuple(models)
        self.transition = check_transition(transition, len(models))
        self.filters = [filter_cls(m, sensors) for m in self.models]
        self.initial_probs = check_initial_probs(initial_probs, len(models))
        self.stats = FilterStats()

    def __repr__(self) -> str:
        names = ", ".join(type(m).__name__ for m in self.models)
        return f"{type(self).__name__}([{names}], filter={type(self.filters[0]).__name__})"

    @property
    def n_models(self) -> int:
        return len(self.models)

    def initialize(self, prior: Gaussian) -> IMMBelief:
        """Every model starts at ``prior`` (batch axes kept) with :attr:`initial_probs`."""
        mean, cov = np.asarray(prior.mean, float), np.asarray(prior.cov, float)
        if mean.shape[-1] != self.models[0].dim:
            raise ShapeError(
                invalid("prior.mean.shape", mean.shape, f"(..., {self.models[0].dim})")
            )
        batch = np.broadcast_shapes(mean.shape[:-1], cov.shape[:-2])
        m, d = self.n_models, mean.shape[-1]
        return IMMBelief(
            np.broadcast_to(mean[..., None, :], (*batch, m, d)).copy(),
            np.broadcast_to(cov[..., None, :, :], (*batch, m, d, d)).copy(),
            np.broadcast_to(self.initial_probs, (*batch, m)).copy(),
        )

    def predict(
        self, belief: IMMBelief, dt: float, rng: np.random.Generator | None = None
    ) -> IMMBelief:
        """Mixing, then each model's prediction; ``probs`` become the predicted ``c_j``."""
        x0, p0, c = imm_mix(belief.means, belief.covs, belief.probs, self.transition)
        means, covs = [], []
        for j, f in enumerate(self.filters):
            g = f.predict(Gaussian(x0[..., j, :], p0[..., j, :, :]), dt)
            means.append(g.mean)
            covs.append(g.cov)
        return IMMBelief(np.stack(means, axis=-2), np.stack(covs, axis=-3), c)

    def update(
        self,
        belief: IMMBelief,
        measurements: Sequence[Measurement] | Measurement,
        rng: np.random.Generator | None = None,
    ) -> IMMBelief:
        """Each model's update; ``mu_j ∝ Lambda_j c_j`` in the log domain."""
        means, covs, lls = [], [], []
        for j, f in enumerate(self.filters):
            g, ll = f.update_with_likelihood(
                Gaussian(belief.means[..., j, :], belief.covs[..., j, :, :]), measurements
            )
            means.append(g.mean)
            covs.append(g.cov)
            lls.append(ll)
        with np.errstate(divide="ignore"):
            log_mu = np.log(belief.probs) + np.stack(lls, axis=-1)
        log_mu = np.where(np.isnan(log_mu), -np.inf, log_mu)
        norm = logsumexp(log_mu, axis=-1, keepdims=True)
        bad = ~np.isfinite(norm)
        if np.any(bad):  # every model's likelihood vanished: keep the predicted probabilities
            self.stats.degenerate_steps += 1
        probs = np.where(bad, belief.probs, np.exp(log_mu - np.where(bad, 0.0, norm)))
        return IMMBelief(np.stack(means, axis=-2), np.stack(covs, axis=-3), probs)

    def filter_stats(self) -> dict[str, Any]:
        """The IMM's own counters plus the sums of its model filters'."""
        out = self.stats.as_dict()
        for f in self.filters:
            for k, v in f.stats.as_dict().items():
                out[k] = out.get(k, 0) + v
        return out
