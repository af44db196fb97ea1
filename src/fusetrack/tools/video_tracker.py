"""The joint visual and wireless tracker of Nott (2009) as one chain, frame by frame.

For every video frame (time ``t_k``)::

    for each radio fix of the subject's tag with time in (t_{k-1}, t_k]:    (Nott 2009, Sec. 3.2.2)
        predict to the fix's time; update with the fix (C = [I2 0], R_z)    (Eqs. 3.32-3.34)
    predict to t_k
    mask  <- background subtraction (Horprasert et al. or MOG2)              (Sec. 4.1)
    blobs <- cleaned, area-filtered, fragments merged                         (Secs. 4.4-4.5)
    occluded <- fewer blobs than tags in view, or no blob in the gate around the predicted
                foot pixel, or the gated blob is much shorter than the person (Sec. 4.5 + spec)
    if not occluded and the frame is not dropped: EKF update with the blob's bottom point
                (variant "foot", V2, what the thesis's real experiments tracked) or its
                bottom and top points (V4) or its bounding box (V8)                  (Eqs. 3.35-3.36, corrected)

The filter is :class:`~fusetrack.filters.ExtendedKalmanFilter` on the
:class:`~fusetrack.motion.WalkingPerson` state with a :class:`~fusetrack.sensors.PositionFix`
(the tag) and a :class:`~fusetrack.sensors.HomographyCamera` (the camera).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core import ConfigError, Gaussian, Measurement, invalid
from ..filters import ExtendedKalmanFilter
from ..motion import WalkingPerson
from ..perception import Blob, HorprasertModel, Mog2Subtractor, detect_occlusion, find_blobs
from ..sensors import (
    HomographyCamera,
    PositionFix,
    apply_homography,
    back_project,
    invert_homography,
)


@dataclass
class TrackerConfig:
    """Everything the chain needs besides the frames and the radio log."""

    foot_homography: NDArray[np.float64]
    head_homography: NDArray[np.float64] | None = None
    tag_cov: NDArray[np.float64] = field(default_factory=lambda: np.diag([0.36, 0.16]))
    sigma_px: float = 1.0
    variant: str = "foot"
    image_size: tuple[int, int] = (640, 480)
    q_a: float = (
        2.0  # m/s^2: people in video turn and stop (the simulation's 0.5 lags a curving walk)
    )
    q_w: float = 0.05
    q_h: float = 1e-3
    person_height: float = 1.75
    background: str = "horprasert"  # or "mog2"
    detection_rate: float = 0.9999
    min_area: int = 150
    merge_gap: int | None = 10
    use_gating: bool = True
    width_rule: bool = True
    drop_frames: tuple[int, int] | None = (
        None  # visual updates skipped on frames [a, b] (inclusive)
    )

    def __post_init__(self) -> None:
        self.foot_homography = np.asarray(self.foot_homography, float)
        invert_homography(self.foot_homography)  # refuses a singular homography
        if self.head_homography is not None:
            self.head_homography = np.asarray(self.head_homography, float)
            invert_homography(self.head_homography)
        if self.variant not in ("foot", "head_foot"):
            raise ConfigError(invalid("variant", self.variant, "'foot' or 'head_foot'"))
        if self.variant == "head_foot" and self.head_homography is None:
            raise ConfigError(
                invalid("head_homography", None, "a 3x3 matrix for variant 'head_foot'")
            )
        if self.background not in ("horprasert", "mog2"):
            raise ConfigError(invalid("background", self.background, "'horprasert' or 'mog2'"))


@dataclass(frozen=True)
class FrameResult:
    """What the chain decided and estimated at one frame."""

    frame: int
    time: float
    x: float
    y: float
    vx: float
    vy: float
    cov_xx: float
    cov_xy: float
    cov_yy: float
    u: float
    v: float
    foot_u: float
    foot_v: float
    radio_x: float
    radio_y: float
    occluded: bool
    reason: str
    n_blobs: int
    n_tags: int
    updated_visual: bool
    box: tuple[int, int, int, int] | None

    def as_row(self) -> dict[str, Any]:
        d = self.__dict__.copy()
        box = d.pop("box")
        d.update(dict(zip(("box_u0", "box_v0", "box_u1", "box_v1"), box or (np.nan,) * 4)))
        return d


class VideoRadioTracker:
    """The chain of the module docstring for one tagged subject (other tags count people)."""

    def __init__(self, config: TrackerConfig) -> None:
        self.cfg = config
        self.motion = WalkingPerson(q_a=config.q_a, q_h=config.q_h, q_w=config.q_w)
        self.tag = PositionFix("tag", cov=config.tag_cov, position_index=(0, 1))
        self.camera = HomographyCamera(
            "camera",
            foot_homography=config.foot_homography,
            head_homography=config.head_homography,
            variant=config.variant,  # type: ignore[arg-type]
            sigma_px=config.sigma_px,
            image_size=config.image_size,
        )
        self.filter = ExtendedKalmanFilter(self.motion, {"tag": self.tag, "camera": self.camera})
        self.background: HorprasertModel | Mog2Subtractor | None = None
        self.belief: Gaussian | None = None
        self.t_prev: float | None = None

    # -- set-up ---------------------------------------------------------------------------------

    def train_background(self, frames: NDArray[np.uint8]) -> None:
        """Learn the empty scene from frames ``(N, H, W, 3)``."""
        if self.cfg.background == "mog2":
            self.background = Mog2Subtractor().train(frames)
        else:
            self.background = HorprasertModel.train(frames, detection_rate=self.cfg.detection_rate)

    def _start(self, xy: NDArray[np.float64], t: float) -> None:
        self.belief = Gaussian(
            np.array([xy[0], xy[1], self.cfg.person_height, 0.5, 0.0, 0.0]),
            np.diag([1.0, 1.0, 0.01, 0.04, 1.0, 1.0]),
        )
        self.t_prev = t

    def _predict_to(self, t: float) -> None:
        assert self.belief is not None and self.t_prev is not None
        if t > self.t_prev + 1e-9:
            self.belief = self.filter.predict(self.belief, t - self.t_prev)
            self.t_prev = t

    # -- the loop -------------------------------------------------------------------------------

    def foreground(self, image: NDArray[np.uint8]) -> NDArray[np.bool_]:
        if self.background is None:
            raise ConfigError("the background model is not trained: call train_background first")
        return self.background.foreground(image)

    def detect(self, image: NDArray[np.uint8]) -> list[Blob]:
        """Background subtraction and blobs of one frame."""
        return find_blobs(
            self.foreground(image), min_area=self.cfg.min_area, merge_gap=self.cfg.merge_gap
        )

    def run(
        self,
        frames: Iterable[tuple[int, float, NDArray[np.uint8]]],
        radio: NDArray[np.float64],
        others: NDArray[np.float64] | None = None,
    ) -> Iterator[FrameResult]:
        """Track through ``frames`` ``(index, time, RGB image)``; see :meth:`track`."""
        return self.track(((k, t, self.detect(image)) for k, t, image in frames), radio, others)

    def track(
        self,
        detections: Iterable[tuple[int, float, list[Blob]]],
        radio: NDArray[np.float64],
        others: NDArray[np.float64] | None = None,
    ) -> Iterator[FrameResult]:
        """Track through per-frame blobs ``(index, time, blobs)``.

        ``radio`` ``(n, 3)`` = (time, x, y) fixes of the subject's tag, in time order, on the video's
        clock; ``others`` ``(n, 4)`` = (time, x, y, tag number) for every other tag (they only count
        people in view).
        """
        radio = np.asarray(radio, float).reshape(-1, 3)
        others = np.zeros((0, 4)) if others is None else np.asarray(others, float).reshape(-1, 4)
        r = 0
        last_fix = np.full(2, np.nan)
        for k, t, blobs in detections:
            while r < len(radio) and radio[r, 0] <= t + 1e-9:
                tr, zx, zy = radio[r]
                if self.belief is None:
                    self._start(np.array([zx, zy]), tr)
                self._predict_to(tr)
                assert self.belief is not None
                self.belief = self.filter.update(
                    self.belief, [Measurement(tr, "tag", np.array([zx, zy]))]
                )
                last_fix = np.array([zx, zy])
                r += 1
            if self.belief is None and blobs:  # no radio fix yet: start from the largest blob
                self._start(back_project(self.cfg.foot_homography, np.array(blobs[0].foot)), t)
            if self.belief is None:
                continue
            self._predict_to(t)
            yield self._visual_step(k, t, blobs, last_fix, self._tags_in_view(t, others))

    def _tags_in_view(self, t: float, others: NDArray[np.float64]) -> int:
        """The subject plus other tags with a fix in the last second that projects into the image."""
        n = 1
        if len(others):
            recent = others[(others[:, 0] <= t + 1e-9) & (others[:, 0] > t - 1.0)]
            for tag_id in np.unique(recent[:, 3]):
                fix = recent[recent[:, 3] == tag_id][-1, 1:3]
                u, v = apply_homography(self.cfg.foot_homography, fix)
                w, h = self.cfg.image_size
                n += int(0 <= u < w and 0 <= v < h)
        return n

    def _measurement(self, blob: Blob) -> NDArray[np.float64]:
        if self.cfg.variant == "foot":
            return np.array(blob.foot)
        return np.array([*blob.foot, *blob.head])

    def _visual_step(
        self, k: int, t: float, blobs: list[Blob], last_fix: NDArray[np.float64], n_tags: int
    ) -> FrameResult:
        assert self.belief is not None
        x = self.belief.mean
        D = self.camera.jacobian(x)[:2]
        S = D @ self.belief.cov @ D.T + self.cfg.sigma_px**2 * np.eye(2)
        pred = self.camera.predict(x)
        height = None
        if self.cfg.head_homography is not None:
            head = apply_homography(self.cfg.head_homography, x[:2])
            height = float(pred[1] - head[1])
        # the person's width in pixels at the foot: w times the image scale along the floor x axis
        width = float(abs(x[3]) * np.hypot(D[0, 0], D[1, 0]))
        dec = detect_occlusion(
            blobs,
            n_tags,
            predicted_foot=pred[:2],
            innovation_cov=S + 4.0 * np.eye(2),  # + blob extraction error (2 px)
            predicted_height=height,
            predicted_width=width if self.cfg.width_rule else None,
            use_gating=self.cfg.use_gating,
        )
        dropped = (
            self.cfg.drop_frames is not None
            and self.cfg.drop_frames[0] <= k <= self.cfg.drop_frames[1]
        )
        updated = False
        if not dec.occluded and not dropped and dec.blob is not None:
            self.belief = self.filter.update(
                self.belief, [Measurement(t, "camera", self._measurement(dec.blob))]
            )
            updated = True
        m, c = self.belief.mean, self.belief.cov
        u, v = apply_homography(self.cfg.foot_homography, m[:2])
        foot = dec.blob.foot if dec.blob is not None else (np.nan, np.nan)
        return FrameResult(
            k,
            t,
            float(m[0]),
            float(m[1]),
            float(m[4]),
            float(m[5]),
            float(c[0, 0]),
            float(c[0, 1]),
            float(c[1, 1]),
            float(u),
            float(v),
            float(foot[0]),
            float(foot[1]),
            float(last_fix[0]),
            float(last_fix[1]),
            bool(dec.occluded),
            "dropped" if dropped and not dec.occluded else dec.reason,
            dec.n_blobs,
            dec.n_tags,
            updated,
            dec.blob.box if dec.blob is not None else None,
        )


__all__ = ["FrameResult", "TrackerConfig", "VideoRadioTracker"]
