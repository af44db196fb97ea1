"""The elliptical head contour as a measurement model over Canny edge frames (Zhai 2007,
Sec. 3.5.2, Eqs. 49-52).

The head is an ellipse with horizontal semi-axis ``a`` and vertical ``b`` centred at the state's
position. ``K`` rays leave the centre at ``theta_k = 2 pi k / K``; the predicted boundary point on
ray k is ``r_k (cos theta_k, sin theta_k)`` with ``r_k = a b / sqrt(b^2 cos^2 + a^2 sin^2)``
(Eq. 49; the thesis prints ``c_k = sqrt(a^2 b^2 / (b^2 + a^2 tan^2))``, ``d_k = tan c_k``, which
loses the sign for ``cos theta_k < 0``). Edge points found along ray k within ``search`` px of the
predicted boundary point are the measurements of that ray; per ray (Eq. 51)::

    p_k(z | x) = q_0 + sum_j N((u_kj, v_kj); boundary_k(x), sigma^2 I)

and ``p(z | x) = prod_k p_k`` (Eq. 52). Sampling: the ray is sampled every ``step`` px (each sample counts ``step``: a sum per unit
length) in a copy of the edge map dilated by a 3 x 3 cross. Canny edges are one pixel wide and
8-connected, and a ray crossing them diagonally between two pixels would see nothing (a third of
the rays of a drawn ellipse did, and the likelihood then peaked 2-3 px off the true centre); the
dilated (4-connected) edges cannot be jumped. ``q_0 = N(3 sigma; 0, sigma^2)`` (2-D form) is the clutter
floor the spec adds so that a ray with no edge does not zero the product (Isard-Blake style).

:class:`EllipseEdgeSensor` is a fusetrack sensor whose measurement ``z`` is the flattened edge
map of one frame (``m = H W``), so every particle filter can weight with it. For the EKF channels
of PF-SP-PEKF / MMPF-SP it is also a *linearised pseudo-measurement of the centre*: around a
channel's predicted centre ``c`` the nearest edge on each ray gives a signed distance ``s_k``
along the ray, and ``residual(z, c) = (sum_k d_k d_k^T)^-1 sum_k s_k d_k`` (least squares over the
rays that found an edge, ``d_k`` the ray direction) with ``H = [I_2, 0]`` and covariance
``sigma^2 (sum_k d_k d_k^T)^-1 = (2 sigma^2 / K) I``. The spec's suggestion, stacking the K edge
points as 2-D observations of the centre, would halve the correction: each ray sees only the
displacement along itself (the aperture problem), which the least-squares form accounts for.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, ShapeError, invalid

Array = NDArray[np.float64]
_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
_CHUNK = 4096  # particles per gather block (bounds the (N, K, S) temporaries)


def edge_map(
    frame: NDArray[np.uint8], smooth: float = 1.0, low: int = 50, high: int = 150
) -> Array:
    """Canny edges ``(H, W)`` in {0, 1} of a Gaussian-smoothed (``smooth`` px) grey frame."""
    img: NDArray[np.uint8] = np.asarray(frame, dtype=np.uint8)
    if img.ndim == 3:
        img = np.asarray(cv2.cvtColor(img, cv2.COLOR_RGB2GRAY), dtype=np.uint8)
    if img.ndim != 2:
        raise ShapeError(invalid("frame.shape", img.shape, "(H, W) or (H, W, 3)"))
    if smooth > 0:
        img = np.asarray(cv2.GaussianBlur(img, (0, 0), smooth), dtype=np.uint8)
    return (cv2.Canny(img, low, high) > 0).astype(np.float64)


def ellipse_rays(a: float, b: float, n_rays: int) -> tuple[Array, Array]:
    """Ray directions ``(K, 2)`` and boundary radii ``(K,)`` (Zhai 2007, Eq. 49, sign-correct)."""
    if a <= 0 or b <= 0:
        raise ConfigError(invalid("axes", (a, b), "two positive semi-axes (px)"))
    th = 2 * np.pi * np.arange(n_rays) / n_rays
    c, s = np.cos(th), np.sin(th)
    r = a * b / np.sqrt((b * c) ** 2 + (a * s) ** 2)
    return np.stack([c, s], axis=-1), r


@dataclass(frozen=True)
class EllipseEdgeSensor:
    """Edge likelihood of an ellipse ``axes = (a, b)`` px on ``height x width`` frames.

    >>> s = EllipseEdgeSensor("head", 60, 80, axes=(10.0, 12.0))
    >>> img = np.zeros((60, 80), np.uint8)
    >>> _ = cv2.ellipse(img, (40, 30), (10, 12), 0, 0, 360, 255, -1)
    >>> z = s.measurement(edge_map(img))
    >>> ll = s.log_likelihood(z, np.array([[40.0, 30.0, 0, 0], [30.0, 30.0, 0, 0]]))
    >>> bool(ll[0] > ll[1])
    True
    """

    sensor_id: str
    height: int
    width: int
    axes: tuple[float, float] = (14.0, 18.0)
    n_rays: int = 24
    sigma: float = 3.0
    search: int = 15
    step: float = 1.0  # px between samples along a ray
    position_index: tuple[int, ...] = (0, 1)
    dim: int = 2  # of the linearised centre pseudo-measurement (the frame itself has H W entries)
    angular: tuple[bool, ...] = (False, False)
    _dirs: Array = field(init=False, repr=False, compare=False)
    _radii: Array = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.n_rays < 3:
            raise ConfigError(invalid("n_rays", self.n_rays, "an integer >= 3"))
        if self.sigma <= 0 or self.search < 1 or not 0 < self.step <= 1:
            raise ConfigError(
                invalid(
                    "sigma/search/step", (self.sigma, self.search, self.step), "> 0 / >= 1 / (0, 1]"
                )
            )
        d, r = ellipse_rays(*self.axes, self.n_rays)
        object.__setattr__(self, "_dirs", d)
        object.__setattr__(self, "_radii", r)

    def with_axes(self, axes: tuple[float, float]) -> EllipseEdgeSensor:
        """The same sensor for another ellipse size."""
        return EllipseEdgeSensor(
            self.sensor_id,
            self.height,
            self.width,
            axes,
            self.n_rays,
            self.sigma,
            self.search,
            self.step,
            self.position_index,
        )

    @property
    def clutter_floor(self) -> float:
        """``q_0 = N(3 sigma; 0, sigma^2 I)`` in 2-D."""
        return float(np.exp(-4.5) / (2 * np.pi * self.sigma**2))

    @property
    def pad(self) -> int:
        """Zero border (px) around the frame in ``z``: every ray sample of a centre inside the
        frame (or one pixel out) stays inside the padded frame."""
        return int(np.ceil(self._radii.max())) + self.search + 2

    def measurement(self, edges: ArrayLike) -> Array:
        """``z``: the edge map ``(H, W)``, dilated by a 3 x 3 cross, zero-padded by :attr:`pad`,
        flattened."""
        e = np.asarray(edges, dtype=np.float64)
        if e.shape != (self.height, self.width):
            raise ShapeError(invalid("edges.shape", e.shape, f"({self.height}, {self.width})"))
        thick = cv2.dilate((e > 0).astype(np.uint8), _CROSS)  # see the module docstring
        return np.pad(thick.astype(np.float64), self.pad).reshape(-1)

    @property
    def value_size(self) -> int:
        """Length of ``z`` (the padded edge frame), which the Gaussian filters check instead of
        ``dim``: they read ``z`` only through :meth:`residual`."""
        return (self.height + 2 * self.pad) * (self.width + 2 * self.pad)

    def _edges(self, z: ArrayLike) -> Array:
        e = np.asarray(z, dtype=np.float64)
        n = self.value_size
        if e.shape[-1] != n or e.size != n:
            raise ShapeError(
                invalid("z.shape", e.shape, f"one padded edge frame of {n} values (no run batch)")
            )
        return e.reshape(-1)

    def _offsets(self) -> tuple[Array, Array]:
        """Along-ray offsets ``s (S,)`` and sample points relative to the centre ``(K, S, 2)``."""
        n = round(self.search / self.step)
        s = self.step * np.arange(-n, n + 1, dtype=np.float64)
        pts = (self._radii[:, None] + s[None, :])[..., None] * self._dirs[:, None, :]
        return s, pts

    def _hits(self, edges: Array, centres: Array) -> Array:
        """Edge values at the ray samples around each centre: ``(M, K, S)`` (0 outside the frame).

        Centres and offsets are rounded to whole pixels separately (a flat-index gather into the
        zero-padded frame; at most one pixel from rounding the sum).
        """
        _, pts = self._offsets()
        pad = self.pad
        wp = self.width + 2 * pad
        off = np.rint(pts[..., 1]).astype(np.int64) * wp + np.rint(pts[..., 0]).astype(np.int64)
        col = np.clip(np.rint(centres[:, 0]), -1, self.width).astype(np.int64)
        row = np.clip(np.rint(centres[:, 1]), -1, self.height).astype(np.int64)
        base = (row + pad) * wp + (col + pad)
        inside = (np.abs(centres[:, 0] - col) <= 0.5) & (np.abs(centres[:, 1] - row) <= 0.5)
        hits = edges[base[:, None, None] + off[None]]
        return np.where(inside[:, None, None], hits, 0.0)

    def _positions(self, x: ArrayLike) -> Array:
        xa = np.asarray(x, dtype=np.float64)
        return xa[..., list(self.position_index)]

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> Array:
        """``log p(z | x) - K log q_0`` (Eqs. 51-52 with the clutter floor) for ``x (..., d)``."""
        edges = self._edges(z)
        pos = self._positions(x)
        flat = pos.reshape(-1, 2)
        s, _ = self._offsets()
        # sum over the edge points on the ray (Eq. 51) as a sum over samples ``step`` apart
        g = self.step * np.exp(-0.5 * (s / self.sigma) ** 2) / (2 * np.pi * self.sigma**2)
        q0 = self.clutter_floor
        out = np.empty(len(flat))
        for i in range(0, len(flat), _CHUNK):
            hits = self._hits(edges, flat[i : i + _CHUNK])
            out[i : i + _CHUNK] = np.sum(np.log1p(hits @ g / q0), axis=-1)
        return out.reshape(pos.shape[:-1])

    # --- the linearised centre pseudo-measurement used by EKF channels -----------------------
    def predict(self, x: ArrayLike) -> Array:
        return self._positions(x)

    def jacobian(self, x: ArrayLike) -> Array:
        xa = np.asarray(x, dtype=np.float64)
        jac = np.zeros((*xa.shape[:-1], 2, xa.shape[-1]))
        jac[..., 0, self.position_index[0]] = 1.0
        jac[..., 1, self.position_index[1]] = 1.0
        return jac

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``sigma^2 (sum_k d_k d_k^T)^-1`` (all rays found)."""
        info = self._dirs.T @ self._dirs
        return np.asarray(self.sigma**2 * np.linalg.inv(info), dtype=np.float64)

    def fisher_information(self, x: ArrayLike) -> Array:
        """``H^T R^-1 H`` of the centre pseudo-measurement, ``(..., d, d)``."""
        H = self.jacobian(x)
        return np.asarray(
            np.swapaxes(H, -1, -2) @ np.linalg.inv(self.noise_cov()) @ H, dtype=np.float64
        )

    def detection_probability(self, x: ArrayLike) -> Array:
        """1 while the centre is in the frame (a contour is always searched), else 0."""
        c = self._positions(x)
        inside = (c[..., 0] >= 0) & (c[..., 0] < self.width) & (c[..., 1] >= 0)
        return np.asarray(inside & (c[..., 1] < self.height), dtype=np.float64)

    def simulate(self, x: ArrayLike, rng: np.random.Generator) -> Array:
        """``z`` for a noise-free outline of the ellipse at ``x (d,)`` (one-pixel line); real
        frames come from a renderer (:mod:`fusetrack.world.head_video`) and :func:`edge_map`."""
        c = self._positions(x)
        if c.ndim != 1:
            raise ShapeError(invalid("x.shape", np.shape(x), "(d,): one state"))
        img = np.zeros((self.height, self.width), np.uint8)
        one = 16
        centre = (round(float(c[0]) * one), round(float(c[1]) * one))
        axes = (round(self.axes[0] * one), round(self.axes[1] * one))
        cv2.ellipse(img, centre, axes, 0, 0, 360, 1, 1, cv2.LINE_8, 4)
        return self.measurement(img)

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> Array:
        """Least-squares centre correction from the nearest edge on each ray around ``z_pred``.

        ``z_pred (..., 2)`` predicted centres; rays without an edge are left out; with fewer than
        three rays found the correction is 0 (no information). Between two centres ``z (..., 2)``
        (the UKF's sigma-point spread) it is their difference.
        """
        if np.shape(z)[-1] == 2:
            return np.asarray(np.asarray(z, np.float64) - np.asarray(z_pred, np.float64))
        edges = self._edges(z)
        c = np.asarray(z_pred, dtype=np.float64)
        flat = c.reshape(-1, 2)
        s, _ = self._offsets()
        hits = self._hits(edges, flat) > 0  # (M, K, S)
        dist = np.where(hits, np.abs(s), np.inf)
        j = np.argmin(dist, axis=-1)
        found = np.isfinite(np.min(dist, axis=-1))  # (M, K)
        # the dilated edge is 3 px thick: take the middle of the run that starts at the nearest
        # hit and goes away from the predicted boundary point (j, j + sgn, j + 2 sgn)
        sgn = np.sign(s[j]).astype(np.int64)
        start = np.where(sgn == 0, j - 1, j)
        step = np.where(sgn == 0, 1, sgn)
        idx = np.clip(start[..., None] + step[..., None] * np.arange(3), 0, len(s) - 1)
        run = np.take_along_axis(hits, idx, axis=-1)
        n_run = np.maximum(run.sum(axis=-1), 1)
        sk = np.where(found, (run * s[idx]).sum(axis=-1) / n_run, 0.0)
        d = self._dirs
        A = np.einsum("mk,ki,kj->mij", found.astype(float), d, d)
        rhs = np.einsum("mk,ki->mi", sk, d)
        enough = found.sum(axis=-1) >= 3
        A = np.where(enough[:, None, None], A, np.eye(2))
        delta = np.linalg.solve(A, rhs[..., None])[..., 0]
        return np.where(enough[:, None], delta, 0.0).reshape(c.shape)
