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

Bad input: a camera outside the room or inside a static occluder is refused (``ConfigError``). A
camera whose field of view holds no particle (e.g. one that faces a wall) is assigned to none: its
NaN readings change nothing, and a reading from it makes every particle impossible (``-inf``), which
:class:`~fusetrack.filters.waypoint_asir.WaypointASIR` answers by ignoring that step's readings.
Singular occluder covariances are regularised by :class:`~fusetrack.world.occlusion.OccluderPriors`.

Two corrections to the printed model, both off by default (``floor = 0``, ``exclusion = 0`` is
the paper as printed):

* ``floor``: ``p(eta | u)`` of a particle that every reporting camera can see is at least
  ``floor``. The extremes of Sec. 6.1 and the clamped Eq. 8 give ``p = 0`` to particles whose
  seen/not-seen pattern contradicts the occluder knowledge; when the whole predicted cloud is a
  little off (the object just behind a disc, a thin shadow no particle reached) every weight is
  zero, the readings are lost and the tracker drifts away from a correct fix. A small floor keeps
  the Gaussian part of Eq. 6 pulling the cloud back.
* ``exclusion``: the rectangle ``A_i(x)`` of Eq. 7 ends ``exclusion`` before ``x``. All the
  rectangles of a particle meet at ``x``, so near ``x`` approximation (d) of Eq. 8 (disjoint
  rectangles) fails: an occluder prior close to the object puts mass in every camera's rectangle,
  ``sum_i q_ij > 1``, the clamped factor is 0 and even the true position gets ``p = 0``. An occluder
  cannot stand within ``D`` of the object (they would overlap), so ``exclusion = D`` removes exactly
  the impossible part of the rectangles where they overlap.

``occlusion_power`` (default 1, the paper) tempers the occlusion evidence: ``p(eta | u)`` enters as
``p^gamma``. Eq. 6 treats each step's seen/not-seen pattern as new evidence given the current
priors, but a real occluder that hides the object usually does so for many steps in a row; with
priors coarser than ``D`` the same event is then counted again every step. ``gamma < 1`` counts it
as fewer independent looks (a diagnosis of ``ercan2013-prior-calibration``, not the paper's model).

A filter reads the network through :class:`OcclusionAwareCameraSensor`: each step's readings,
selected cameras and occluder knowledge travel as one :class:`CameraNetworkReport` (a
:class:`~fusetrack.core.Measurement` value) and ``log_likelihood(report, x)`` scores positions.

:meth:`OcclusionAwareLikelihood.log_likelihood` is one Numba pass over the particles
(:func:`fusetrack.world.occlusion_kernels.camera_likelihood_kernel`);
:meth:`OcclusionAwareLikelihood.log_likelihood_reference` is the NumPy composition of the
building blocks it replaces (the tests compare them).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, MeasurementError, ShapeError, check_points, invalid
from ..world.geometry import Array
from ..world.occlusion import (
    OccluderPriors,
    disks_block,
    occlusion_probability_reference,
    pattern_probability,
)
from ..world.occlusion_kernels import camera_likelihood_kernel
from ..world.room import Room
from .perspective_camera import CameraArray

_CameraArgs = tuple[Array, Array, Array, Array, Array, Array, Array]
"""The camera arrays of :func:`camera_likelihood_kernel` for one selection."""

PriorMode = Literal["gaussian", "perfect", "none"]
PRIOR_MODES = ("gaussian", "perfect", "none")


@dataclass(frozen=True)
class OcclusionAwareLikelihood:
    """``log f(Z | u)`` for a camera network in a room with static and moving occluders."""

    cameras: CameraArray
    room: Room
    diameter: float = 3.33
    prior_mode: PriorMode = "gaussian"
    floor: float = 0.0
    exclusion: float = 0.0
    occlusion_power: float = 1.0
    _camera_args: dict[bytes, _CameraArgs] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        if self.prior_mode not in PRIOR_MODES:
            raise ConfigError(invalid("prior_mode", self.prior_mode, f"one of {PRIOR_MODES}"))
        if not self.diameter >= 0:
            raise ConfigError(invalid("diameter", self.diameter, "a number >= 0"))
        if not 0 <= self.floor < 1:
            raise ConfigError(invalid("floor", self.floor, "a probability in [0, 1)"))
        if not 0 <= self.exclusion < np.inf:
            raise ConfigError(invalid("exclusion", self.exclusion, "a finite length >= 0"))
        if not 0 < self.occlusion_power <= 1:
            raise ConfigError(
                invalid("occlusion_power", self.occlusion_power, "a number in (0, 1]")
            )
        # A camera behind a wall would look through it: a convex room's walls are not tested
        # for sight (every inside point sees every other), so such a camera must be refused here.
        outside = ~self.room.free(self.cameras.positions)
        if np.any(outside):
            raise ConfigError(
                invalid(
                    "camera position",
                    [self.cameras.ids[i] for i in np.flatnonzero(outside)],
                    "cameras inside the room, not in a wall or static occluder",
                )
            )

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

    def _inputs(
        self, z: ArrayLike, selected: ArrayLike, x: ArrayLike
    ) -> tuple[Array, NDArray[np.intp], Array]:
        """Readings ``(K,)``, camera indices ``(K,)`` and particle positions ``(L, 2)``, checked:
        indices in range, one reading each (NaN: not seen, inf refused), finite positions."""
        sel = np.asarray(selected, dtype=np.intp).reshape(-1)
        n = len(self.cameras.positions)
        if sel.size and not (sel.min() >= 0 and sel.max() < n):
            raise ConfigError(invalid("selected", sel.tolist(), f"camera indices in [0, {n})"))
        zz = np.asarray(z, float).reshape(-1)
        if zz.shape != sel.shape:
            raise ShapeError(
                invalid("z.shape", zz.shape, f"one reading per selected camera {sel.shape}")
            )
        if np.isinf(zz).any():
            raise MeasurementError(invalid("z", zz.tolist(), "finite readings, NaN where unseen"))
        return zz, sel, check_points("x", np.asarray(x, float)[..., :2])

    def _occluder_arrays(
        self, occluders: OccluderPriors | ArrayLike | None
    ) -> tuple[int, Array, Array]:
        """Kernel mode (0 none, 1 known centres, 2 Gaussian priors), means, covariances."""
        none = np.zeros((0, 2)), np.zeros((0, 2, 2))
        if self.prior_mode == "none":
            return 0, *none
        if self.prior_mode == "perfect":
            if occluders is None:
                return 1, *none
            centres = (
                occluders.mean
                if isinstance(occluders, OccluderPriors)
                else check_points("occluders", occluders)
            )
            return 1, np.ascontiguousarray(centres), none[1]
        if not isinstance(occluders, OccluderPriors):
            raise ConfigError(
                invalid(
                    "occluders",
                    type(occluders).__name__,
                    "OccluderPriors for prior_mode='gaussian'",
                )
            )
        return 2, np.ascontiguousarray(occluders.mean), np.ascontiguousarray(occluders.cov)

    def _cameras_of(self, sel: NDArray[np.intp]) -> _CameraArgs:
        """The kernel's camera arrays of the selected cameras: positions, yaws, tan(fov/2), focal
        lengths and the variances of Eq. 2, made once per distinct selection (a run queries few)."""
        key = sel.tobytes()
        if key not in self._camera_args:
            cams = self.cameras.subset(sel)
            self._camera_args[key] = (
                np.ascontiguousarray(cams.positions),
                np.ascontiguousarray(cams.yaws, dtype=float),
                np.tan(cams.fovs / 2),
                np.ascontiguousarray(cams.focals, dtype=float),
                cams.sigma_theta**2,
                cams.sigma_pos**2,
                cams.sigma_read**2,
            )
        return self._camera_args[key]

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
        One Numba pass (Eq. 6 with Eqs. 2, 7-9 and the partition of Sec. 4.3).
        """
        zz, sel, pts = self._inputs(z, selected, x)
        mode, mu, cov = self._occluder_arrays(occluders)
        positions, yaws, tan_half, focals, var_theta, var_pos, var_read = self._cameras_of(sel)
        edge_a, edge_b = self.room._blocking_edges
        in_static = (
            self.room.in_static_occluder(pts)
            if self.room.static_occluders
            else np.zeros(len(pts), dtype=bool)
        )
        return np.asarray(
            camera_likelihood_kernel(
                pts,
                zz,
                positions,
                yaws,
                tan_half,
                focals,
                var_theta,
                var_pos,
                var_read,
                edge_a,
                edge_b,
                np.ascontiguousarray(in_static),
                mode,
                mu,
                cov,
                float(self.diameter),
                float(self.exclusion),
                float(self.floor),
                float(self.occlusion_power),
            )
        )

    def log_likelihood_reference(
        self,
        z: ArrayLike,
        selected: ArrayLike,
        x: ArrayLike,
        occluders: OccluderPriors | ArrayLike | None = None,
    ) -> Array:
        """NumPy reference of :meth:`log_likelihood` built from the world's occlusion functions."""
        zz, sel, pts = self._inputs(z, selected, x)
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
            _, centres, _ = self._occluder_arrays(occluders)
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
                q = occlusion_probability_reference(
                    cams.positions, x[possible], occluders, self.diameter, self.exclusion
                )
                p[possible] = pattern_probability(q, eta, A[:, possible])
        p = np.where(possible, np.maximum(p, self.floor), 0.0)
        with np.errstate(divide="ignore"):
            return np.asarray(np.where(possible, self.occlusion_power * np.log(p), -np.inf))


@dataclass(frozen=True, eq=False)
class CameraNetworkReport:
    """One step's :class:`~fusetrack.core.Measurement` value for the camera network (Alg. 3):
    ``readings (K,)`` of the queried cameras ``selected (K,)`` (indices), NaN where a camera did
    not see the object, and what is known of the moving occluders at that step (the priors for
    ``"gaussian"``, the centres ``(M, 2)`` for ``"perfect"``, None for ``"none"``)."""

    readings: Array
    selected: NDArray[np.intp]
    occluders: OccluderPriors | Array | None = None


@dataclass(frozen=True)
class OcclusionAwareCameraSensor:
    """The sensor model a filter uses: ``log f(Z | u)`` (Eq. 6) of a :class:`CameraNetworkReport`
    for particle positions ``x (L, 2)``, read by ``likelihood``."""

    likelihood: OcclusionAwareLikelihood
    sensor_id: str = "cameras"

    def log_likelihood(self, z: CameraNetworkReport, x: Array) -> Array:
        if not isinstance(z, CameraNetworkReport):
            raise MeasurementError(
                invalid(f"value of {self.sensor_id!r}", type(z).__name__, "a CameraNetworkReport")
            )
        return self.likelihood.log_likelihood(z.readings, z.selected, x, z.occluders)
