"""Blobs from a foreground mask: clean-up, connected components, fragment merging, and the
measurements the tracker needs -- bottom point (foot), top point (head) and bounding box
(Nott 2009, Secs. 4.4-4.5, 5.2.1).

* Clean-up: a 3x3 opening removes speckle, a 7x7 closing fills holes; 8-connected components
  smaller than ``min_area`` pixels are dropped (the thesis gives no numbers; these are the spec's).
* Top and bottom points are "the extremum of the blobs" (Sec. 4.4): here the mean column of the
  blob's pixels in its ``band`` top-most (bottom-most) rows, at the top (bottom) row.
* One person may fall apart into several blobs (Fig. 5.10: a hand). :func:`merge_fragments`
  joins blobs whose boxes overlap vertically and lie within ``gap`` pixels horizontally, so the
  blob count means people (the occlusion rule counts blobs); :func:`largest_blob` is the thesis's
  rule for a single subject.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...core import ShapeError, invalid

_OPEN = cv2.getStructuringElement(cv2.MORPH_RECT, (3, 3))
_CLOSE = cv2.getStructuringElement(cv2.MORPH_RECT, (7, 7))


@dataclass(frozen=True)
class Blob:
    """One foreground region: ``area`` (px), ``box = (u_min, v_min, u_max, v_max)`` (inclusive),
    ``foot = (u, v)`` (bottom point), ``head = (u, v)`` (top point), and its member labels."""

    area: int
    box: tuple[int, int, int, int]
    foot: tuple[float, float]
    head: tuple[float, float]
    labels: tuple[int, ...]

    @property
    def height(self) -> int:
        return self.box[3] - self.box[1] + 1


def clean_mask(mask: ArrayLike, open_size: int = 3, close_size: int = 7) -> NDArray[np.uint8]:
    """Opening then closing of a boolean mask; returns ``uint8`` 0/1."""
    m = np.asarray(mask)
    if m.ndim != 2:
        raise ShapeError(invalid("mask.shape", m.shape, "(H, W)"))
    m8 = m.astype(np.uint8)
    k_open = (
        _OPEN if open_size == 3 else cv2.getStructuringElement(cv2.MORPH_RECT, (open_size,) * 2)
    )
    k_close = (
        _CLOSE if close_size == 7 else cv2.getStructuringElement(cv2.MORPH_RECT, (close_size,) * 2)
    )
    if open_size > 1:
        m8 = np.asarray(cv2.morphologyEx(m8, cv2.MORPH_OPEN, k_open), dtype=np.uint8)
    if close_size > 1:
        m8 = np.asarray(cv2.morphologyEx(m8, cv2.MORPH_CLOSE, k_close), dtype=np.uint8)
    return m8


def _blob(
    labels: NDArray[np.int32], members: tuple[int, ...], box: tuple[int, int, int, int], band: int
) -> Blob:
    u0, v0, u1, v1 = box
    sub = np.isin(labels[v0 : v1 + 1, u0 : u1 + 1], members)
    rows, cols = np.nonzero(sub)
    area = int(rows.size)
    top = rows < rows.min() + band
    bottom = rows > rows.max() - band
    head = (float(cols[top].mean() + u0), float(rows.min() + v0))
    foot = (float(cols[bottom].mean() + u0), float(rows.max() + v0))
    return Blob(area, box, foot, head, members)


def find_blobs(
    mask: ArrayLike,
    *,
    min_area: int = 150,
    clean: bool = True,
    merge_gap: int | None = 10,
    band: int = 3,
) -> list[Blob]:
    """Blobs of a foreground mask, largest first (cleaned, area-filtered, fragments merged
    when ``merge_gap`` is not None)."""
    m = clean_mask(mask) if clean else np.asarray(mask).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(m, connectivity=8)
    boxes: list[tuple[tuple[int, ...], tuple[int, int, int, int]]] = []
    for k in range(1, n):
        x, y, w, h, area = (int(v) for v in stats[k])
        if area >= min_area:
            boxes.append(((k,), (x, y, x + w - 1, y + h - 1)))
    if merge_gap is not None:
        boxes = merge_fragments(boxes, merge_gap)
    lab = np.asarray(labels, dtype=np.int32)
    blobs = [_blob(lab, members, box, band) for members, box in boxes]
    return sorted(blobs, key=lambda b: -b.area)


def merge_fragments(
    boxes: list[tuple[tuple[int, ...], tuple[int, int, int, int]]], gap: int
) -> list[tuple[tuple[int, ...], tuple[int, int, int, int]]]:
    """Join boxes that overlap vertically and are within ``gap`` px horizontally, until none do."""
    items = list(boxes)
    changed = True
    while changed:
        changed = False
        for i in range(len(items)):
            for j in range(i + 1, len(items)):
                (la, a), (lb, b) = items[i], items[j]
                v_overlap = min(a[3], b[3]) - max(a[1], b[1]) >= 0
                h_gap = max(a[0], b[0]) - min(a[2], b[2])
                if v_overlap and h_gap <= gap:
                    box = (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))
                    items[i] = (la + lb, box)
                    del items[j]
                    changed = True
                    break
            if changed:
                break
    return items


def largest_blob(blobs: list[Blob]) -> Blob | None:
    """The thesis's single-subject rule: "the blob with the largest area" (Nott 2009, Sec. 4.5)."""
    return max(blobs, key=lambda b: b.area) if blobs else None


__all__ = ["Blob", "clean_mask", "find_blobs", "largest_blob", "merge_fragments"]
