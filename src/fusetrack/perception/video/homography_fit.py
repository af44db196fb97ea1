"""Fitting the floor and head-plane homographies (Nott 2009, Secs. 4.4, 5.1, 5.2.2).

* :func:`fit_homography` -- the normalised direct linear transform (Hartley & Zisserman 2004,
  Alg. 4.2): the thesis says only "the homography can be obtained by using singular value
  decomposition". Pairs ``(X, Y) <-> (u, v)`` give two rows each,
  ``[X, Y, 1, 0, 0, 0, -uX, -uY, -u]`` and ``[0, 0, 0, X, Y, 1, -vX, -vY, -v]``; ``h`` is the
  right singular vector of the smallest singular value. Optionally RANSAC + refinement through
  ``cv2.findHomography``. A walk that does not spread across the floor (the thesis's "single
  straight line", blamed for a head homography ">20 pixels" off) is refused unless
  ``check=False``: the ratio of the minor to the major standard deviation of the world points
  must reach ``min_spread``.
* :func:`calibrate_from_checkerboard` -- the thesis's simulation camera came from "a chequered
  board and the Camera Calibration toolbox": corners by ``cv2.findChessboardCorners``, intrinsics
  and pose by ``cv2.calibrateCamera`` (one floor view: principal point fixed at the image centre,
  square pixels, no distortion), then ``H_f = K [r1 r2 t]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...core import ConfigError, ShapeError, invalid
from ...sensors import apply_homography

Array = NDArray[np.float64]


class DegenerateGeometryError(ConfigError):
    """The points cannot determine a homography (too few, collinear, or not spread out)."""


@dataclass(frozen=True)
class HomographyFit:
    """A fitted homography ``H`` (world -> image, ``H[2, 2] = 1``) with its diagnostics:
    ``rms_px`` reprojection RMS on the fitting pairs, ``spread`` = minor/major standard deviation
    of the world points, ``sv_ratio`` = smallest / second-smallest singular value of the DLT
    system (near 1: undetermined), ``inliers`` (RANSAC) and ``n``."""

    H: Array
    rms_px: float
    spread: float
    sv_ratio: float
    inliers: NDArray[np.bool_]
    n: int


def _normaliser(p: Array) -> Array:
    """Hartley normalisation: centroid to the origin, mean distance sqrt(2)."""
    c = p.mean(0)
    d = np.linalg.norm(p - c, axis=1).mean()
    s = np.sqrt(2.0) / max(d, 1e-12)
    return np.array([[s, 0, -s * c[0]], [0, s, -s * c[1]], [0, 0, 1.0]])


def spread_ratio(world: ArrayLike) -> float:
    """Minor over major standard deviation of 2-D points (0: collinear)."""
    w = np.asarray(world, float)
    ev = np.linalg.eigvalsh(np.cov(w.T)) if len(w) > 1 else np.zeros(2)
    return float(np.sqrt(max(ev[0], 0.0) / ev[1])) if ev[1] > 0 else 0.0


def dlt(world: ArrayLike, image: ArrayLike) -> tuple[Array, float]:
    """Normalised DLT: ``(H, sv_ratio)`` with ``H[2, 2] = 1``."""
    w = np.asarray(world, float)
    im = np.asarray(image, float)
    tw, ti = _normaliser(w), _normaliser(im)
    wn = w @ tw[:2, :2].T + tw[:2, 2]
    imn = im @ ti[:2, :2].T + ti[:2, 2]
    X, Y = wn[:, 0], wn[:, 1]
    u, v = imn[:, 0], imn[:, 1]
    one, zero = np.ones_like(X), np.zeros_like(X)
    a = np.empty((2 * len(w), 9))
    a[0::2] = np.column_stack([X, Y, one, zero, zero, zero, -u * X, -u * Y, -u])
    a[1::2] = np.column_stack([zero, zero, zero, X, Y, one, -v * X, -v * Y, -v])
    _, s, vt = np.linalg.svd(a)
    hn = vt[-1].reshape(3, 3)
    H = np.linalg.inv(ti) @ hn @ tw
    return H / H[2, 2], float(s[-1] / s[-2]) if s[-2] > 0 else 1.0


def fit_homography(
    world: ArrayLike,
    image: ArrayLike,
    *,
    method: str = "dlt",
    ransac_px: float = 10.0,
    min_spread: float = 0.25,
    check: bool = True,
) -> HomographyFit:
    """Fit ``H`` with ``image ~ pi(H [world; 1])`` from ``n >= 4`` pairs ``(n, 2)``.

    ``method``: ``"dlt"`` (the thesis's SVD) or ``"ransac"`` (``cv2.findHomography`` with a
    ``ransac_px`` inlier threshold and Levenberg-Marquardt refinement). Raises
    :class:`DegenerateGeometryError` when the world points are too few or (with ``check``) do not
    spread across the floor.
    """
    w = np.asarray(world, float)
    im = np.asarray(image, float)
    if w.ndim != 2 or w.shape[1] != 2 or im.shape != w.shape:
        raise ShapeError(invalid("(world, image) shapes", (w.shape, im.shape), "two equal (n, 2)"))
    ok = np.isfinite(w).all(1) & np.isfinite(im).all(1)
    w, im = w[ok], im[ok]
    if len(w) < 4:
        raise DegenerateGeometryError(invalid("number of point pairs", len(w), ">= 4 finite pairs"))
    spread = spread_ratio(w)
    if check and spread < min_spread:
        raise DegenerateGeometryError(
            invalid(
                "training walk spread (minor/major std of the floor points)",
                round(spread, 3),
                f">= {min_spread}: the walk must cover the floor, not a line (Nott 2009, Sec. 5.2.2)",
            )
        )
    inliers = np.ones(len(w), bool)
    if method == "dlt":
        H, svr = dlt(w, im)
    elif method == "ransac":
        import cv2

        H, mask = cv2.findHomography(w, im, cv2.RANSAC, ransac_px)
        if H is None:
            raise DegenerateGeometryError(
                "cv2.findHomography found no homography: points degenerate"
            )
        inliers = mask.ravel().astype(bool)
        H = H / H[2, 2]
        svr = dlt(w[inliers], im[inliers])[1]
    else:
        raise ConfigError(invalid("method", method, "'dlt' or 'ransac'"))
    err = reprojection_errors(H, w, im)
    return HomographyFit(
        H, float(np.sqrt(np.mean(err[inliers] ** 2))), spread, svr, inliers, len(w)
    )


def reprojection_errors(H: ArrayLike, world: ArrayLike, image: ArrayLike) -> Array:
    """Pixel distances between ``pi(H [world; 1])`` and ``image``, ``(n,)``."""
    projected = apply_homography(H, world)
    return np.asarray(np.linalg.norm(projected - np.asarray(image, float), axis=1))


@dataclass(frozen=True)
class CheckerboardCalibration:
    K: Array
    R: Array
    t: Array
    H_floor: Array
    rms_px: float


def calibrate_from_checkerboard(
    image: ArrayLike, pattern: tuple[int, int], square: float, origin: ArrayLike = (0.0, 0.0)
) -> CheckerboardCalibration:
    """Camera from one view of a checkerboard lying on the floor (see the module docstring).

    ``pattern`` = inner corners ``(columns, rows)``; ``square`` = square size (m); the board's
    first inner corner is at floor point ``origin`` and its rows run along +X, columns along +Y.
    """
    import cv2

    img = np.asarray(image)
    gray = cv2.cvtColor(img, cv2.COLOR_RGB2GRAY) if img.ndim == 3 else img.astype(np.uint8)
    found, corners = cv2.findChessboardCorners(gray, pattern)
    if not found:
        raise DegenerateGeometryError(
            f"no {pattern[0]}x{pattern[1]} checkerboard found in the image"
        )
    corners = cv2.cornerSubPix(
        gray,
        corners,
        (5, 5),
        (-1, -1),
        (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4),
    )
    obj = _board_points(pattern, square, origin)
    cols, rows = pattern
    grid = corners.reshape(rows, cols, 2).astype(np.float64)
    h, w = gray.shape
    k0 = np.array([[max(h, w), 0, w / 2.0], [0, max(h, w), h / 2.0], [0, 0, 1.0]])
    flags = (
        cv2.CALIB_USE_INTRINSIC_GUESS
        | cv2.CALIB_FIX_PRINCIPAL_POINT
        | cv2.CALIB_FIX_ASPECT_RATIO
        | cv2.CALIB_ZERO_TANGENT_DIST
        | cv2.CALIB_FIX_K1
        | cv2.CALIB_FIX_K2
        | cv2.CALIB_FIX_K3
    )
    # OpenCV may list the corners starting from any corner of the board; of the four orders,
    # the right one puts the camera above the floor (Z up) with the smallest reprojection error
    best = None
    for flip_r in (False, True):
        for flip_c in (False, True):
            g = grid[::-1] if flip_r else grid
            g = g[:, ::-1] if flip_c else g
            img_pts = g.reshape(-1, 2)
            rms, K, _dist, rvecs, tvecs = cv2.calibrateCamera(
                [obj.astype(np.float32)],
                [img_pts.astype(np.float32)],
                (w, h),
                k0.copy(),
                np.zeros(5),
                flags=flags,
            )
            R, _ = cv2.Rodrigues(rvecs[0])
            t = tvecs[0].ravel()
            centre = -R.T @ t
            # the origin corner is the board's corner nearest the camera on its left
            key = (-img_pts[0, 1] + 0.25 * img_pts[0, 0], rms)
            if centre[2] > 0 and (best is None or key < best[0]):
                best = (key, K, R, t)
    if best is None:
        raise DegenerateGeometryError("no corner order puts the camera above the checkerboard")
    (_, rms), K, R, t = best
    H = K @ np.column_stack([R[:, 0], R[:, 1], t])
    K64, R64, t64 = (np.asarray(a, dtype=np.float64) for a in (K, R, t))
    return CheckerboardCalibration(K64, R64, t64, np.asarray(H / H[2, 2], np.float64), float(rms))


def _board_points(pattern: tuple[int, int], square: float, origin: ArrayLike) -> Array:
    cols, rows = pattern
    o = np.asarray(origin, float)
    jj, ii = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    pts = np.column_stack(
        [o[0] + ii.ravel() * square, o[1] + jj.ravel() * square, np.zeros(cols * rows)]
    )
    return pts


__all__ = [
    "CheckerboardCalibration",
    "DegenerateGeometryError",
    "HomographyFit",
    "calibrate_from_checkerboard",
    "dlt",
    "fit_homography",
    "reprojection_errors",
    "spread_ratio",
]
