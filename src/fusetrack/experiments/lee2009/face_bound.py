"""What no method can beat on lee2009-face-matching's simulated model (issue 19, item 3): the
accuracy of the Bayes-optimal classifier, beside the identification and walking-direction tables.

**Identification.** A query is :func:`~fusetrack.perception.synthetic_face` of a person drawn
uniformly from the population, seen from an angle uniform in ``[0, pi]``: every pixel and channel
is its mean colour (background, the person's skin or hair, by the head and hair masks of the
angle) plus ``N(0, noise^2)``, clipped to ``[0, 1]``. A classifier that knows every person's
colours and sees the query's pixels (:class:`FaceOracle`) picks the person of the largest exact
likelihood, the angle integrated out: it enters only through the hair line, a step function of
the angle, so the integral is a finite sum over the hair masks with their probabilities
(:func:`hair_masks`, :func:`mask_probabilities`); a clipped channel (exactly 0 or 1) contributes
``Phi`` of its tail, the others the Gaussian density. With equal priors this is the MAP rule,
the most accurate of all rules on the model (Bayes; Duda, Hart & Stork 2001, Sec. 2.2). The
"multi-view reference" method is told the view's bin (the motion cue), so the classifier is told
it too (``window``). The methods see the query's pixels (through its histogram) and noisy
references of the same colours, which, given the colours, say nothing about who the query is:
no method is more accurate. From the back, people with the same hair look alike (the hair covers
the head), so even this classifier errs there.

**Walking direction.** The direction is uniform over the 8 compass points; each camera reports the
(lateral, size) sign pattern of :func:`~fusetrack.perception.apparent_motion`, each non-zero sign
flipped with probability ``f`` independently; a zero (motion along the line of sight, or across
it) stays zero. The exact accuracy of any rule is a finite sum over directions and flip patterns
(:func:`direction_accuracy`); the Bayes rule (:func:`bayes_direction`) takes the direction of the
largest likelihood ``prod (1 - f)^kept f^flipped`` among those whose zeros match.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.special import log_ndtr, logsumexp

from ...core import ConfigError, invalid
from ...perception import CAMERA_VIEWS, COMPASS, apparent_motion, synthetic_face

Array = np.ndarray
Colour = tuple[float, float, float]
Observation = dict[str, tuple[int, int]]

_MARK_SKIN, _MARK_HAIR = (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)  # colours that label the masks


HAIR_LINE = (-0.6, 0.9)
"""The hair line of :func:`~fusetrack.perception.synthetic_face` at views 0 and pi (linear between)."""


@lru_cache(maxsize=8)
def hair_masks(size: int) -> tuple[Array, Array, Array]:
    """The masks a view in ``[0, pi]`` can give: ``(edges, skin, hair)``, mask ``i`` for the
    hair line in ``[edges[i], edges[i + 1])`` (``skin``, ``hair`` boolean ``(M, size, size)``),
    drawn by :func:`~fusetrack.perception.synthetic_face` itself (noise 0, marker colours). The
    hair line changes the masks only where it crosses a pixel row."""
    rows = np.arange(size) / (size - 1) * 2 - 1
    lo, hi = HAIR_LINE
    edges = np.concatenate([[lo], np.unique(rows[(rows > lo) & (rows < hi)]), [hi]])
    views = ((edges[:-1] + edges[1:]) / 2 - lo) / (hi - lo) * math.pi
    rng = np.random.default_rng(0)  # unused: noise 0
    imgs = np.stack([synthetic_face(v, _MARK_SKIN, _MARK_HAIR, rng, size, 0.0) for v in views])
    return edges, np.all(imgs == 0.0, axis=-1), np.all(imgs == 1.0, axis=-1)


def mask_probabilities(edges: Array, window: tuple[float, float] = (0.0, math.pi)) -> Array:
    """``P(mask i)`` for a view uniform in ``window`` (within ``[0, pi]``): the share of the
    window's hair lines in ``[edges[i], edges[i + 1])``."""
    a, b = window
    if not 0.0 <= a < b <= math.pi:
        raise ConfigError(invalid("window", window, "0 <= start < end <= pi"))
    lo, hi = HAIR_LINE
    la, lb = lo + (hi - lo) * a / math.pi, lo + (hi - lo) * b / math.pi
    overlap = np.clip(np.minimum(edges[1:], lb) - np.maximum(edges[:-1], la), 0.0, None)
    return np.asarray(overlap / (lb - la))


def clipped_gaussian_loglik(x: Array, mean: Array | float, sigma: float) -> Array:
    """Log-likelihood of ``clip(mean + N(0, sigma^2), 0, 1) = x`` per entry: ``log Phi(-mean /
    sigma)`` at 0, ``log Phi((mean - 1) / sigma)`` at 1, the Gaussian log-density between
    (``x`` and ``mean`` broadcast)."""
    x, m = np.broadcast_arrays(np.asarray(x, float), np.asarray(mean, float))
    out = -0.5 * ((x - m) / sigma) ** 2 - math.log(sigma * math.sqrt(2 * math.pi))
    low, high = x <= 0.0, x >= 1.0
    out[low] = log_ndtr(-m[low] / sigma)
    out[high] = log_ndtr((m[high] - 1.0) / sigma)
    return out


def pixel_logliks(pixels: Array, colours: Array, sigma: float) -> Array:
    """``(C, N)``: the log-likelihood of each pixel ``(N, 3)`` if its mean were each colour
    ``(C, 3)``, summed over the channels: :func:`clipped_gaussian_loglik` as a quadratic form
    (one matrix product) with the clipped channels' terms swapped for their tails."""
    x, m = np.asarray(pixels, float), np.asarray(colours, float)
    log_norm = math.log(sigma * math.sqrt(2 * math.pi))
    sq = (x * x).sum(1)[None, :] - 2.0 * m @ x.T + (m * m).sum(1)[:, None]
    out = -0.5 * sq / sigma**2 - x.shape[1] * log_norm
    for edge, tail in ((0.0, log_ndtr(-m / sigma)), (1.0, log_ndtr((m - 1.0) / sigma))):
        hit = (x <= 0.0) if edge == 0.0 else (x >= 1.0)
        gauss = -0.5 * ((edge - m) / sigma) ** 2 - log_norm  # what the quadratic form counted
        out += (tail - gauss) @ hit.T.astype(float)
    return out


@dataclass(frozen=True, eq=False)
class FaceOracle:
    """The Bayes-optimal identification of a query patch among ``people`` (``(skin, hair)``
    colours) on the model of :func:`~fusetrack.perception.synthetic_face` (module docstring)."""

    people: Sequence[tuple[Colour, Colour]]
    noise: float
    size: int = 40
    background: Colour = (0.2, 0.25, 0.3)
    _masks: tuple[Array, Array, Array] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.noise > 0:
            raise ConfigError(invalid("noise", self.noise, "a pixel noise > 0"))
        if not self.people:
            raise ConfigError(invalid("people", self.people, "at least one (skin, hair) pair"))
        edges, skin, hair = hair_masks(self.size)
        flat = [m.reshape(len(edges) - 1, -1).astype(float) for m in (skin, hair)]
        object.__setattr__(self, "_masks", (edges, *flat))

    def log_likelihoods(self, image: Array, window: tuple[float, float] = (0.0, math.pi)) -> Array:
        """``log p(image | person k)`` ``(K,)``, the view integrated out uniformly over
        ``window`` (module docstring)."""
        edges, flat_skin, flat_hair = self._masks  # (M, N) each
        with np.errstate(divide="ignore"):
            log_p = np.log(mask_probabilities(edges, window))
        px = np.asarray(image, float).reshape(-1, 3)
        colours = np.array([self.background, *(c for person in self.people for c in person)])
        per = pixel_logliks(px, colours, self.noise)  # (1 + 2 K, N)
        bg = per[0]
        skins = (per[1::2] - bg).T  # (N, K): a pixel's change from background to skin
        hairs = (per[2::2] - bg).T
        ll = bg.sum() + flat_skin @ skins + flat_hair @ hairs + log_p[:, None]  # (M, K)
        return np.asarray(logsumexp(ll, axis=0))

    def classify(self, image: Array, window: tuple[float, float] = (0.0, math.pi)) -> int:
        """The person of the largest posterior (equal priors), the view uniform over ``window``:
        the Bayes decision."""
        return int(np.argmax(self.log_likelihoods(image, window)))


def _patterns() -> Array:
    """Predicted (lateral, size) signs ``(8, 2 C)``: row = compass direction, in ``COMPASS``
    order; columns camera by camera in ``CAMERA_VIEWS`` order."""
    return np.array(
        [
            [s for v in CAMERA_VIEWS.values() for s in apparent_motion(v, COMPASS[d])]
            for d in COMPASS
        ]
    )


def direction_likelihoods(observed: Array, flip: float) -> Array:
    """``P(observed | direction)`` ``(M, 8)`` for sign rows ``observed`` ``(M, 2 C)``: each
    non-zero predicted sign kept with ``1 - flip``, flipped with ``flip``; a zero is observed as
    zero, never flipped."""
    obs = np.asarray(observed)[:, None, :]
    pred = _patterns()[None]
    p = np.where(pred == 0, obs == 0, np.where(obs == pred, 1.0 - flip, (obs == -pred) * flip))
    return np.asarray(p.prod(axis=-1))


def possible_observations() -> Array:
    """Every sign row ``(M, 2 C)`` some direction and flip pattern give (each once)."""
    rows = set()
    for pred in _patterns():
        nz = np.flatnonzero(pred)
        for flips in itertools.product((1, -1), repeat=len(nz)):
            row = pred.copy()
            row[nz] *= flips
            rows.add(tuple(int(v) for v in row))
    return np.array(sorted(rows))


def as_observation(row: Array) -> Observation:
    """A sign row as the ``{camera: (lateral, size)}`` a rule reads."""
    return {c: (int(row[2 * i]), int(row[2 * i + 1])) for i, c in enumerate(CAMERA_VIEWS)}


def bayes_direction(observed: Observation, flip: float) -> str:
    """The compass direction of the largest likelihood (uniform prior; the first on a tie): the
    Bayes decision."""
    row = np.array([[s for c in CAMERA_VIEWS for s in observed[c]]])
    return list(COMPASS)[int(np.argmax(direction_likelihoods(row, flip)[0]))]


def direction_accuracy(rule: Callable[[Observation], str] | None, flip: float) -> float:
    """Exact accuracy over a uniform direction and every flip pattern: ``sum_obs P(obs |
    rule(obs)) / 8``; ``rule=None`` is the Bayes rule, ``sum_obs max_d P(obs | d) / 8``, the
    most accurate of all rules."""
    if not 0.0 <= flip <= 1.0:
        raise ConfigError(invalid("flip", flip, "a probability in [0, 1]"))
    obs = possible_observations()
    lik = direction_likelihoods(obs, flip)
    if rule is None:
        return float(lik.max(axis=1).sum() / len(COMPASS))
    names = list(COMPASS)
    chosen = [names.index(rule(as_observation(row))) for row in obs]
    return float(lik[np.arange(len(obs)), chosen].sum() / len(COMPASS))


__all__ = [
    "HAIR_LINE",
    "FaceOracle",
    "as_observation",
    "bayes_direction",
    "clipped_gaussian_loglik",
    "direction_accuracy",
    "direction_likelihoods",
    "hair_masks",
    "mask_probabilities",
    "pixel_logliks",
    "possible_observations",
]
