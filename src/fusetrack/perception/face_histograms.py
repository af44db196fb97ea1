"""Colour-histogram face matching with multi-view references, and walking direction from cameras
(Lee 2009, Sec. 5.2.1).

* A face is an ``m``-bin colour pdf (Eqs. 5.1-5.2); similarity is the Bhattacharyya coefficient
  ``rho = sum_u sqrt(p(u) q(u))`` in ``[0, 1]`` (Eq. 5.5).
* A single frontal reference fails when the candidate is seen from the side or the back; the
  proposal keeps ``N = pi / dtheta + 1`` reference pdfs at viewing angles ``0, dtheta, ..., pi``
  (Eq. 5.6, the printed "pi/theta" is a typo; faces assumed left/right symmetric) and takes the
  best match over them.
* Walking direction: a face moving past cameras at known places moves left or right in each
  image and grows or shrinks; the pattern over cameras tells the direction (Figs. 5-8, 5-9).

The dissertation's images are not available; :func:`synthetic_face` draws small face patches
(skin ellipse, hair cap that covers more of the head as the view turns to the back, background).
"""

from __future__ import annotations

import math

import numpy as np

from ..core import ConfigError, ShapeError, invalid

Array = np.ndarray

COMPASS = {
    "N": (0.0, 1.0),
    "NE": (math.sqrt(0.5), math.sqrt(0.5)),
    "E": (1.0, 0.0),
    "SE": (math.sqrt(0.5), -math.sqrt(0.5)),
    "S": (0.0, -1.0),
    "SW": (-math.sqrt(0.5), -math.sqrt(0.5)),
    "W": (-1.0, 0.0),
    "NW": (-math.sqrt(0.5), math.sqrt(0.5)),
}
# Cameras 1-5 of Figs. 5-8/5-9 as viewing directions: 1, 2 look east, 3 north, 4 west, 5 south
# (the layout that reproduces the text's N and NE examples).
CAMERA_VIEWS = {
    "1": (1.0, 0.0),
    "2": (1.0, 0.0),
    "3": (0.0, 1.0),
    "4": (-1.0, 0.0),
    "5": (0.0, -1.0),
}


def colour_histogram(image: Array, bins: int = 8, mask: Array | None = None) -> Array:
    """Joint RGB histogram with ``bins`` per channel (``bins^3`` bins), normalised to sum 1 (Eqs. 5.1-5.2)."""
    img = np.asarray(image, float)
    if img.ndim != 3 or img.shape[2] != 3:
        raise ShapeError(invalid("image.shape", img.shape, "(H, W, 3) RGB in [0, 1]"))
    if not 1 <= bins <= 256:
        raise ConfigError(invalid("bins", bins, "1..256 per channel"))
    q = np.clip((img * bins).astype(int), 0, bins - 1)
    idx = (q[..., 0] * bins + q[..., 1]) * bins + q[..., 2]
    if mask is not None:
        idx = idx[np.asarray(mask, bool)]
    h = np.bincount(idx.ravel(), minlength=bins**3).astype(float)
    if h.sum() == 0:
        raise ShapeError(invalid("mask", "no pixel", "at least one pixel"))
    return h / h.sum()


def bhattacharyya(p: Array, q: Array) -> float:
    """``sum_u sqrt(p(u) q(u))`` (Lee 2009, Eq. 5.5): 1 for identical pdfs, 0 for disjoint ones."""
    p, q = np.asarray(p, float), np.asarray(q, float)
    if p.shape != q.shape:
        raise ShapeError(invalid("q.shape", q.shape, f"{p.shape} like p"))
    if np.any(p < 0) or np.any(q < 0):
        raise ConfigError(invalid("pdf", "negative entries", "non-negative histograms"))
    return float(np.sum(np.sqrt(p / p.sum() * q / q.sum())))


def n_views(dtheta: float) -> int:
    """``N = pi / dtheta + 1`` reference views from the front to the back (Eq. 5.6)."""
    if not 0 < dtheta <= math.pi:
        raise ConfigError(invalid("dtheta", dtheta, "in (0, pi] rad"))
    return round(math.pi / dtheta) + 1


def best_match(candidate: Array, references: list[Array]) -> float:
    """The best Bhattacharyya coefficient of a candidate over a person's reference views."""
    return max(bhattacharyya(candidate, r) for r in references)


def synthetic_face(
    view: float,
    skin: tuple[float, float, float],
    hair: tuple[float, float, float],
    rng: np.random.Generator,
    size: int = 40,
    noise: float = 0.03,
) -> Array:
    """A head patch seen from ``view`` radians (0 = front, pi = back): skin ellipse and hair cap."""
    yy, xx = np.mgrid[0:size, 0:size] / (size - 1) * 2 - 1
    img = np.empty((size, size, 3))
    img[:] = (0.2, 0.25, 0.3)  # background
    head = (xx / 0.7) ** 2 + (yy / 0.9) ** 2 <= 1
    v = abs(math.remainder(view, 2 * math.pi)) / math.pi  # 0 front ... 1 back
    hair_line = -0.6 + 1.5 * v  # a cap at the front, most of the head from the back
    is_hair = head & (yy < hair_line)
    img[head] = skin
    img[is_hair] = hair
    img += noise * rng.standard_normal(img.shape)
    return np.clip(img, 0, 1)


def apparent_motion(view_dir: tuple[float, float], walk: tuple[float, float]) -> tuple[int, int]:
    """(lateral, size) signs in a camera looking along ``view_dir`` for a face walking ``walk``.

    lateral +1 = moves right in the image, size +1 = grows (approaching).
    """
    d = np.asarray(view_dir, float)
    right = np.array([d[1], -d[0]])  # image right = viewing direction turned clockwise
    w = np.asarray(walk, float)
    lat, depth = float(right @ w), float(d @ w)
    return (int(np.sign(round(lat, 9))), int(-np.sign(round(depth, 9))))


def walking_direction(observed: dict[str, tuple[int, int]]) -> str:
    """The compass direction whose predicted (lateral, size) pattern agrees with the most observations."""
    if not observed:
        raise ConfigError(invalid("observed", observed, "at least one camera's observation"))
    unknown = set(observed) - set(CAMERA_VIEWS)
    if unknown:
        raise ConfigError(invalid("camera", sorted(unknown), f"cameras {sorted(CAMERA_VIEWS)}"))

    def score(name: str) -> int:
        return sum(
            int(apparent_motion(CAMERA_VIEWS[c], COMPASS[name])[i] == obs[i])
            for c, obs in observed.items()
            for i in (0, 1)
        )

    return max(COMPASS, key=score)
