"""nott2009-video's PCRB (issue 19): on frames without the camera it is the Kalman filter's
covariance of the trackers' tag-only model, the camera's frames follow the rendering and the
trackers' updates, and the report shows the bound beside the trackers with claims that fail
when a tracker beats it."""

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.evaluation import ClaimKinds
from fusetrack.experiments.nott2009 import best_possible as bp
from fusetrack.experiments.nott2009 import video_best_possible as vbp
from fusetrack.filters import KalmanFilter, run_filter
from fusetrack.sensors import default_camera, ground_homography
from fusetrack.tools import TrackerConfig, VideoRadioTracker

KINDS = ClaimKinds({"BP_*": "diagnostic"})
T, DT, TAG_EVERY = 24, 1.0 / 15.0, 3
TRACKER = VideoRadioTracker(
    TrackerConfig(
        foot_homography=ground_homography(default_camera().P), tag_cov=np.diag([0.2, 0.05])
    )
)


def _rows(err: float = 0.5, occluded: bool = True, reason: str = "fewer blobs than tags"):
    """Tracking rows of the three scenes: a straight walk at 1 m/s, every method's error
    ``err``, the subject ``occluded`` on every frame and every tracker's ``reason``."""
    t = np.arange(T) * DT
    rows = []
    for scene, methods in (
        ("single", ["J", "B4", "J-drop", "B4-drop"]),
        ("crossing", ["J", "B4"]),
        ("wall", ["J", "B4"]),
    ):
        for m in methods:
            for run in range(2):
                for k in range(T):
                    dropped = scene == "single" and 5 <= k <= 10
                    rows.append(
                        {
                            "part": "track",
                            "scene": scene,
                            "method": m,
                            "run": run,
                            "frame": k,
                            "time": t[k],
                            "true_x": 2.0 + t[k],
                            "true_y": 6.0,
                            "err_m": err,
                            "b1_err_m": 0.4,
                            "occluded_true": occluded,
                            "dropped": dropped,
                            "reason": "dropped" if dropped and "drop" in m else reason,
                        }
                    )
    return pd.DataFrame(rows)


def test_without_the_camera_the_bound_is_the_kalman_filter_covariance():
    """Camera never (the subject occluded, no tracker updates): the trackers' model is linear
    Gaussian, so the PCRB is exactly the KF's covariance with the tag every 3rd frame."""
    bounds = vbp.estimate(_rows(), TRACKER, DT, TAG_EVERY)
    times = np.arange(T) * DT
    kf = KalmanFilter(TRACKER.motion, {"tag": TRACKER.tag})
    x0 = np.array([2.0, 6.0, 1.75, 0.5, 1.0, 0.0])
    ms = [Measurement(float(times[k]), "tag", x0[:2]) for k in range(0, T, TAG_EVERY)]
    track = run_filter(kf, Gaussian(x0, bp.PRIOR_COV), ms, times=times, t0=0.0)
    assert track.covariances is not None
    want = np.sqrt(np.trace(track.covariances[:, :2, :2], axis1=1, axis2=2).mean())
    for cb in bounds.values():
        assert cb.bound.rms["run"] == pytest.approx(want, rel=1e-9)
        assert cb.bound.rms["window"] == pytest.approx(want, rel=1e-9)  # every frame camera-less
        assert cb.rms["run"]["J"][0] == pytest.approx(0.5)
        assert cb.rms["run"]["B1"][0] == pytest.approx(0.4)


def test_a_sharper_foot_point_lowers_the_bound_where_the_camera_reports():
    df = _rows(occluded=False, reason="visible")
    sharper = VideoRadioTracker(replace(TRACKER.cfg, sigma_px=0.25))
    sens = vbp.noise_sensitivity(df, {"1 px": TRACKER, "0.25 px": sharper}, DT, TAG_EVERY)
    assert sens["PCRB RMS (m)"].iloc[1] < 0.5 * sens["PCRB RMS (m)"].iloc[0]
    # without the camera the pixel noise does not matter
    blind = vbp.noise_sensitivity(_rows(), {"1 px": TRACKER, "0.25 px": sharper}, DT, TAG_EVERY)
    assert blind["PCRB RMS (m)"].iloc[1] == pytest.approx(blind["PCRB RMS (m)"].iloc[0])


def test_the_camera_reports_where_the_subject_is_visible_or_a_tracker_updated():
    visible = vbp.case_rows(_rows(occluded=False, reason="visible"), "single-drop")
    j = visible[visible["method"] == "J"]
    dropped = (j["step"] >= 5) & (j["step"] <= 10)
    assert not j[dropped]["camera"].any()  # J-drop and B4-drop skip frames 5-10
    assert j[~dropped]["camera"].all()
    assert (j["occluded"] == dropped).all()
    # occluded in the rendering, but a tracker took the blob: the bound's camera has it too
    updated = vbp.case_rows(_rows(occluded=True, reason="visible"), "crossing")
    assert updated["camera"].all() and not updated["occluded"].any()
    # with the camera the bound is far below the tag-only one
    with_camera = vbp.estimate(_rows(occluded=False, reason="visible"), TRACKER, DT, TAG_EVERY)
    without = vbp.estimate(_rows(), TRACKER, DT, TAG_EVERY)
    assert with_camera["single"].bound.rms["run"] < 0.5 * without["single"].bound.rms["run"]


def test_report_shows_the_bound_and_the_claims_fail_below_it():
    df = _rows(err=1e-3)
    bounds = vbp.estimate(df, TRACKER, DT, TAG_EVERY)
    sharper = VideoRadioTracker(replace(TRACKER.cfg, sigma_px=0.25))
    sens = vbp.noise_sensitivity(df, {"1 px": TRACKER, "0.25 px": sharper}, DT, TAG_EVERY)
    assert sens["PCRB RMS (m)"].iloc[0] == pytest.approx(bounds["single"].bound.rms["run"])
    text = vbp.report(bounds, 2, sens)
    assert "PCRB RMS (m)" in text and "mean-error bound (m)" in text
    assert f"{bounds['wall'].bound.rms['run']:.3g}" in text
    assert not any(c.holds for c in vbp.claims(KINDS, bounds))  # 1 mm: impossible on the model
    above = vbp.claims(KINDS, vbp.estimate(_rows(err=5.0), TRACKER, DT, TAG_EVERY))
    assert [c.id for c in above] == [f"BP_J_above_bound_{m}" for m in vbp.MODELS]
    assert all(c.holds and c.kind == "diagnostic" for c in above)
