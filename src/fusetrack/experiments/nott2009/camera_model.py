"""Nott (2009): the parts of the camera's measurement model the thesis describes but does not
report (spec items E13, E15).

* Pixel noise from known ground points (Sec. 4.6, spec Sec. 3.15): the subject stands on known
  floor points ``g_k``; ``R_y = cov(BP_k - pi(H_f g_k))`` of the blob's bottom point ``BP_k``.
  The thesis compared ``BP_k`` with the ground-homography image of the *tag's* fix instead, which
  folds the tag's error (about 0.46 m, tens of pixels) into ``R_y``; both are measured.
* The head/foot variant V4 (the thesis's Top Point / Bottom Point, Sec. 3.1 and Fig. 4.2): the
  joint tracker on the blob's head and foot points with the head-plane homography, beside the
  foot-only V2 the thesis's real experiments used.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import Claim, ClaimKinds
from ...perception import HorprasertModel, find_blobs, largest_blob
from ...sensors import NferTagSimulator, apply_homography
from ...world import Person, RoomRenderer, Walk

KNOWN_POINTS = np.array([[x, y] for x in (1.5, 3.5, 5.5, 7.5) for y in np.linspace(1.5, 13.5, 8)])
"""The floor points (m) the subject stands on: the calibration grid of the manual homography."""
GAIT_ZERO_FPS = 1.8
"""Frames at ``k / 1.8`` s catch the renderer's gait (0.9 Hz) with the legs together: standing."""


def pixel_noise_rows(
    renderer: RoomRenderer,
    bgs: HorprasertModel,
    tag: NferTagSimulator,
    foot_homography: np.ndarray,
    rng: np.random.Generator,
    points: np.ndarray = KNOWN_POINTS,
) -> list[dict[str, Any]]:
    """The subject standing on each known point: the blob's bottom point minus the image of the
    point (``*_known``) and of the tag's fix there (``*_tag``, the thesis's Sec. 4.6), in px."""
    walk = Walk(np.arange(len(points)) / GAIT_ZERO_FPS, points)
    fixes = tag.simulate(points, rng)
    known = apply_homography(foot_homography, points)
    tagged = apply_homography(foot_homography, fixes)
    rows: list[dict[str, Any]] = []
    for f in renderer.frames([Person(walk)], rng):
        blob = largest_blob(find_blobs(bgs.foreground(f.image)))
        if blob is None or not np.isfinite(tagged[f.index]).all():
            continue
        bp = np.asarray(blob.foot, float)
        du_k, dv_k = bp - known[f.index]
        du_t, dv_t = bp - tagged[f.index]
        rows.append(
            {
                "part": "pixel_noise",
                "point": f.index,
                "du_known": du_k,
                "dv_known": dv_k,
                "du_tag": du_t,
                "dv_tag": dv_t,
            }
        )
    return rows


@dataclass(frozen=True)
class PixelNoise:
    """Standard deviations and means (px, per image axis u, v) of the two estimates."""

    known_std: tuple[float, float]
    known_mean: tuple[float, float]
    tag_std: tuple[float, float]
    n: int

    @property
    def ratio(self) -> float:
        """How much larger the thesis's estimate is (RMS over the axes of the stds)."""
        return float(np.hypot(*self.tag_std) / max(np.hypot(*self.known_std), 1e-12))


def pixel_noise(df: pd.DataFrame) -> PixelNoise:
    """Estimation: the sample statistics of the residuals over every run's points."""
    d = df[df["part"] == "pixel_noise"]
    known = d[["du_known", "dv_known"]].to_numpy(float)
    tag = d[["du_tag", "dv_tag"]].to_numpy(float)
    return PixelNoise(
        known_std=(float(known[:, 0].std(ddof=1)), float(known[:, 1].std(ddof=1))),
        known_mean=(float(known[:, 0].mean()), float(known[:, 1].mean())),
        tag_std=(float(tag[:, 0].std(ddof=1)), float(tag[:, 1].std(ddof=1))),
        n=len(d),
    )


def v4_rmse(single: pd.DataFrame) -> tuple[float, float]:
    """Joint-tracker floor RMSE (m) on the single-person video: V4 (``J-V4``) and V2 (``J``)."""

    def rmse(method: str) -> float:
        return float(np.sqrt((single[single["method"] == method]["err_m"] ** 2).mean()))

    return rmse("J-V4"), rmse("J")


def camera_model_claims(
    kinds: ClaimKinds, noise: PixelNoise, v4: tuple[float, float], sigma_px: float
) -> list[Claim]:
    """Sec. 3.15 (pixel noise, our way and the thesis's) and V4 against V2."""
    su, sv = noise.known_std
    return [
        kinds.claim(
            "Ry-known",
            "pixel noise from the blob's bottom point on known ground points (Sec. 3.15): std "
            f"per image axis u, v (px); the tracker's {sigma_px:g} px is not optimistic",
            "method only (Sec. 4.6); the simulation assumes 1 px",
            f"{su:.2f}, {sv:.2f}",
            f"both <= {sigma_px:g} px",
            max(su, sv) <= sigma_px,
        ),
        kinds.claim(
            "Ry-thesis",
            "the thesis's way (bottom point against the image of the tag's fix) folds the tag "
            "error into R_y: its std over the known-point one",
            "method only (Sec. 4.6; spec E13: tens of pixels)",
            noise.ratio,
            ">= 5",
            noise.ratio >= 5,
        ),
        kinds.claim(
            "V4-video",
            "single person, no occlusion: joint RMSE with the blob's head and foot points (V4, "
            "head-plane homography) vs foot only (V2) (m)",
            "not reported: the head homography was 'erroneous' (spec E15: report V4)",
            f"{v4[0]:.3f} vs {v4[1]:.3f}",
            "V4 <= 1.5 x V2",
            v4[0] <= 1.5 * v4[1],
        ),
    ]


def camera_model_report(
    noise: PixelNoise,
    v4: tuple[float, float],
    straight_head: float,
    foot_walking: float,
    runs: int,
) -> str:
    """Report text: the two pixel-noise estimates and V4 against V2."""
    (su, sv), (mu, mv), (tu, tv) = noise.known_std, noise.known_mean, noise.tag_std
    return f"""
## The camera's measurement model (Sec. 3.15, V4)

Pixel noise (spec Sec. 3.15): the subject stands on the {len(KNOWN_POINTS)} calibration points
({noise.n} frames over {runs} run(s)); the blob's bottom point against the ground-homography
image of the known point has std {su:.2f} px (u) and {sv:.2f} px (v) and mean {mu:+.2f}, {mv:+.2f} px
(a bias the covariance does not hold). The tracker's 1 px is conservative for a standing
subject; walking, the gait moves the bottom point (median {foot_walking:.2f} px from the true
foot on the single-person video), which the 1 px covers. Against the image of the tag's fix
at the same point, as the thesis's Sec. 4.6 does it, the std is {tu:.1f} px and {tv:.1f} px,
{noise.ratio:.0f} times larger: that is the tag's error, not the camera's.

Head and foot points (V4): on the single-person video, the joint tracker with the blob's top point
and the head-plane homography as a second measurement has a floor RMSE of {v4[0]:.3f} m against
{v4[1]:.3f} m with the foot only (V2). With the head homography fitted from the thesis's straight
training walk (worst error {straight_head:.0f} px above) the head rows would be useless, which is
why the thesis tracked the foot only.
"""
