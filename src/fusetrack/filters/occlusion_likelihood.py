"""The occlusion-aware camera-network likelihood ``f(Z | u)`` of Ercan et al. 2013 (Secs. 4.2-4.3).

A queried camera either reports the object's horizontal image coordinate (it sees it, ``eta_i = 1``)
or NaN (``eta_i = 0``: out of view or occluded). Since ``eta`` is a function of ``Z``,

    f(Z | u) = p(eta | u) prod_{i: eta_i = 1} N(z_i; f_i h_i(x)/d_i(x), var(v_i | x))   # Eq. 6

``p(eta | u)`` depends on what is known about the moving occluders (``prior_mode``):

* ``"gaussian"``: Gaussian priors; Eq. 7 per camera and occluder, Eq. 8 for sets of cameras and
  inclusion-exclusion (Eq. 9) over the occluded ones, on the cameras *assigned* to the particle
  (field of view and static occluders, the geometric partition of Sec. 4.3, Fig. 4);
* ``"perfect"`` (RMSE_occ = 0): occluders are discs at known positions, ``p`` is 1 when ``eta``
  equals the deterministic visibility of the particle and 0 otherwise (Sec. 6.1);
* ``"none"`` (RMSE_occ = RMSE_max): nothing is known; ``p`` is 0 only when a camera claims to see a
  point it cannot see (out of view or behind a static occluder) and 1 otherwise (Sec. 6.1).

Returned log-likelihoods are ``-inf`` for impossible particles, never NaN.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.errors import ConfigError, ShapeError, invalid
from ..sensors.perspective_camera import CameraArray
from ..world.geometry import Array
from ..world.occlusion import (
    OccluderPriors,
    disks_block,
    occlusion_probability,
    pattern_probability,
)
from ..world.room import Room

PriorMode = Literal["gaussian", "perfect", "none"]
PRIOR_MODES = ("gaussian", "perfect", "none")


@dataclass(frozen=True)
class OcclusionAwareLikelihood:
    """``log f(Z | u)`` for a camera network in a room with static and moving occluders."""

    cameras: CameraArray
    room: Room
    diameter: float = 3.33
    prior_mode: PriorMode = "gaussian"

    def __post_init__(self) -> None:
        if self.prior_mode not in PRIOR_MODES:
            raise ConfigError(invalid("prior_mode", self.prior_mode, f"one of {PRIOR_MODES}"))
        if not self.diameter >= 0:
            raise ConfigError(invalid("diameter", self.diameter, "a number >= 0"))

    def assigned(self, selected: NDArray[np.intp], x: Array) -> NDArray[np.bool_]:
        """``(K, L)``: camera ``selected[k]`` has particle l in view, not behind a wall or static occluder."""
        cams = self.cameras.subset(selected)
        in_fov = cams.in_fov(x[:, None, :]).T
        blocked = self.room.sight_blocked_grid(cams.positions, x)
        return np.asarray(in_fov & ~blocked)

    def visible(
        self, selected: NDArray[np.intp], x: Array, occluder_positions: ArrayLike
    ) -> NDArray[np.bool_]:
        """``(K, L)`` deterministic visibility with occluder discs at known positions."""
        cams = self.cameras.subset(selected)
        return self.assigned(selected, x) & ~disks_block(
            cams.positions, x, occluder_positions, self.diameter
        )

    def log_likelihood(
        self,
        z: ArrayLike,
        selected: ArrayLike,
        x: ArrayLike,
        occluders: OccluderPriors | ArrayLike | None = None,
    ) -> Array:
        """``log f(Z | u)`` ``(L,)`` for particle positions ``x (L, 2)``.

        ``z (K,)``: readings of the queried cameras ``selected (K,)`` (indices into
        ``cameras``), NaN where a camera did not see the object. ``occluders``: the priors
        (``"gaussian"``), the true centres ``(M, 2)`` (``"perfect"``), ignored (``"none"``).
        """
        sel = np.asarray(selected, dtype=np.intp).reshape(-1)
        zz = np.asarray(z, float).reshape(-1)
        if zz.shape != sel.shape:
            raise ShapeError(
                invalid("z.shape", zz.shape, f"one reading per selected camera {sel.shape}")
            )
        pts = np.asarray(x, float)[..., :2].reshape(-1, 2)
        eta = np.isfinite(zz)
        A = self.assigned(sel, pts)
        log_p = self._log_pattern(eta, sel, pts, A, occluders)
        if eta.any():
            cams = self.cameras.subset(sel[eta])
            mean = cams.image_coordinate(pts[:, None, :])
            var = cams.noise_var(pts[:, None, :])
            r = zz[eta] - mean
            log_g = -0.5 * np.sum(r * r / var + np.log(2 * np.pi * var), axis=-1)
            log_p = log_p + log_g
        return np.asarray(np.where(np.isnan(log_p), -np.inf, log_p))

    def _log_pattern(
        self,
        eta: NDArray[np.bool_],
        sel: NDArray[np.intp],
        x: Array,
        A: NDArray[np.bool_],
        occluders: OccluderPriors | ArrayLike | None,
    ) -> Array:
        possible = ~np.any(eta[:, None] & ~A, axis=0)
        if self.prior_mode == "none":
            p = possible.astype(float)
        elif self.prior_mode == "perfect":
            if occluders is None or isinstance(occluders, OccluderPriors):
                centres = (
                    occluders.mean if isinstance(occluders, OccluderPriors) else np.zeros((0, 2))
                )
            else:
                centres = np.asarray(occluders, float).reshape(-1, 2)
            cams = self.cameras.subset(sel)
            vis = A & ~disks_block(cams.positions, x, centres, self.diameter)
            p = np.all(vis == eta[:, None], axis=0).astype(float)
        else:
            if not isinstance(occluders, OccluderPriors):
                raise ConfigError(
                    invalid(
                        "occluders",
                        type(occluders).__name__,
                        "OccluderPriors for prior_mode='gaussian'",
                    )
                )
            p = np.zeros(len(x))
            if possible.any():
                cams = self.cameras.subset(sel)
                q = occlusion_probability(cams.positions, x[possible], occluders, self.diameter)
                p[possible] = pattern_probability(q, eta, A[:, possible])
        with np.errstate(divide="ignore"):
            return np.asarray(np.log(p))
