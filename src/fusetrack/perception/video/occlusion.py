"""Occlusion detection (Nott 2009, Sec. 4.5) and blob-to-subject association.

The thesis: "During occlusion the multiple motion blobs combine together to form a huge single
blob ... we can detect occlusion if the number of blobs are less than the number of objects as
identified by the wireless tracker." Counting only works if one person is one blob, hence
:func:`~fusetrack.perception.video.blobs.merge_fragments` before counting; and it misses a person
who walks behind a wall (the blob vanishes while the count of other blobs may still match), hence
the gating rule added here: the subject is also occluded when no blob's bottom point falls
inside the gate around the predicted foot pixel, or when the gated blob is much shorter than the
predicted person (< ``min_height_ratio`` of the predicted head-to-foot height, the spec's rule)
or much narrower (< ``min_width_ratio`` of the predicted width: a person half behind the edge
of a wall still has a foot, but not the right one).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .blobs import Blob


@dataclass(frozen=True)
class OcclusionDecision:
    """Whether the subject is occluded in this frame, why, and the blob to use when it is not."""

    occluded: bool
    reason: str
    blob: Blob | None
    n_blobs: int
    n_tags: int


def count_rule(n_blobs: int, n_tags: int) -> bool:
    """Nott 2009, Sec. 4.5: occluded when there are fewer blobs than tagged people in view."""
    return n_blobs < n_tags


def associate(
    blobs: Sequence[Blob], predicted_foot: ArrayLike, innovation_cov: ArrayLike, gate: float
) -> tuple[Blob | None, float]:
    """The blob whose bottom point is nearest the predicted foot pixel in Mahalanobis distance
    (squared, with the 2x2 innovation covariance), if within ``gate``; else ``(None, best)``."""
    if not blobs:
        return None, float("inf")
    s_inv = np.linalg.inv(np.asarray(innovation_cov, float))
    p = np.asarray(predicted_foot, float)
    d2 = [float((np.subtract(b.foot, p)) @ s_inv @ np.subtract(b.foot, p)) for b in blobs]
    k = int(np.argmin(d2))
    return (blobs[k] if d2[k] <= gate else None), d2[k]


def detect_occlusion(
    blobs: Sequence[Blob],
    n_tags: int,
    *,
    predicted_foot: ArrayLike | None = None,
    innovation_cov: ArrayLike | None = None,
    predicted_height: float | None = None,
    predicted_width: float | None = None,
    gate: float = 13.8155,  # chi-square, 2 dof, 0.999
    min_height_ratio: float = 0.6,
    min_width_ratio: float = 0.8,
    use_gating: bool = True,
) -> OcclusionDecision:
    """Decide whether the subject is occluded and pick its blob (see the module docstring).

    Without a prediction (or with ``use_gating=False``) only the count rule applies and the
    subject's blob is the largest (the thesis's single-subject rule).
    """
    n_b = len(blobs)
    if count_rule(n_b, n_tags):
        return OcclusionDecision(True, "fewer blobs than tags", None, n_b, n_tags)
    if not use_gating or predicted_foot is None or innovation_cov is None:
        best = max(blobs, key=lambda b: b.area) if blobs else None
        return OcclusionDecision(
            best is None, "no blob" if best is None else "visible", best, n_b, n_tags
        )
    blob, _ = associate(blobs, predicted_foot, innovation_cov, gate)
    if blob is None:
        return OcclusionDecision(True, "no blob in the gate", None, n_b, n_tags)
    if predicted_height is not None and blob.height < min_height_ratio * predicted_height:
        return OcclusionDecision(True, "blob shorter than the person", None, n_b, n_tags)
    width = blob.box[2] - blob.box[0] + 1
    if predicted_width is not None and width < min_width_ratio * predicted_width:
        return OcclusionDecision(True, "blob narrower than the person", None, n_b, n_tags)
    return OcclusionDecision(False, "visible", blob, n_b, n_tags)


__all__ = ["OcclusionDecision", "associate", "count_rule", "detect_occlusion"]
