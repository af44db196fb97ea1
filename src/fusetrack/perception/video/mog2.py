"""OpenCV's Gaussian-mixture background subtractor (Zivkovic 2004) as an alternative to
Horprasert et al. (Nott 2009 used the latter). Shadows (value 127) count as background."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray


class Mog2Subtractor:
    """``cv2.createBackgroundSubtractorMOG2`` behind the same ``foreground(frame)`` call."""

    def __init__(
        self, history: int = 200, var_threshold: float = 16.0, detect_shadows: bool = True
    ) -> None:
        import cv2

        self._cv2 = cv2
        self._sub: Any = cv2.createBackgroundSubtractorMOG2(history, var_threshold, detect_shadows)

    def train(self, frames: ArrayLike) -> Mog2Subtractor:
        """Learn the empty scene from frames ``(N, H, W, 3)``."""
        for f in np.asarray(frames):
            self._sub.apply(np.ascontiguousarray(f, dtype=np.uint8), learningRate=-1)
        return self

    def foreground(self, frame: ArrayLike, learning_rate: float = 0.0) -> NDArray[np.bool_]:
        m = self._sub.apply(np.ascontiguousarray(frame, dtype=np.uint8), learningRate=learning_rate)
        return np.asarray(m == 255)


__all__ = ["Mog2Subtractor"]
