"""Nott 2009's camera measurement model (spec Sec. 3.15, E13, E15): the pixel noise measured on
known ground points is the blob's own (well under the tracker's 1 px), the thesis's way against
the tag's fixes folds the tag error in (tens of pixels), and the claims read those numbers."""

import numpy as np
import pandas as pd
import pytest

from fusetrack.evaluation import ClaimKinds
from fusetrack.experiments.nott2009.camera_model import (
    KNOWN_POINTS,
    PixelNoise,
    camera_model_claims,
    pixel_noise,
    pixel_noise_rows,
    v4_rmse,
)
from fusetrack.perception import HorprasertModel
from fusetrack.sensors import NferTagSimulator, default_camera, ground_homography
from fusetrack.world import RoomRenderer

KINDS = ClaimKinds({"Ry-*": "diagnostic", "V4-video": "diagnostic"})


def test_known_points_measure_the_blob_and_the_thesis_way_the_tag():
    rng = np.random.default_rng(4)
    renderer = RoomRenderer()
    bgs = HorprasertModel.train(renderer.empty_frames(10, rng))
    tag = NferTagSimulator("field", sigma=(0.1, 0.1), quantum=0.098, field_seed=4)
    Hf = ground_homography(default_camera().P)
    points = KNOWN_POINTS[::3]
    rows = pixel_noise_rows(renderer, bgs, tag, Hf, rng, points)
    assert len(rows) == len(points)  # the subject is found on every point
    noise = pixel_noise(pd.DataFrame(rows))
    assert max(noise.known_std) < 1.0 and max(abs(m) for m in noise.known_mean) < 2.0
    assert max(noise.tag_std) > 10.0 and noise.ratio > 10


def test_pixel_noise_statistics_by_hand():
    df = pd.DataFrame(
        {
            "part": ["pixel_noise"] * 3 + ["other"],
            "du_known": [1.0, 2.0, 3.0, 99.0],
            "dv_known": [0.0, 0.0, 3.0, 99.0],
            "du_tag": [10.0, 20.0, 30.0, 0.0],
            "dv_tag": [0.0, 0.0, 30.0, 0.0],
        }
    )
    n = pixel_noise(df)
    assert n.n == 3 and n.known_mean == (2.0, 1.0)
    assert n.known_std == pytest.approx((1.0, np.sqrt(3.0)))
    assert n.ratio == pytest.approx(10.0)


def test_claims_read_the_numbers():
    good = PixelNoise((0.2, 0.3), (0.0, 0.1), (20.0, 15.0), 32)
    claims = {c.id: c for c in camera_model_claims(KINDS, good, (0.02, 0.018), 1.0)}
    assert claims["Ry-known"].holds and claims["Ry-thesis"].holds and claims["V4-video"].holds
    bad = PixelNoise((1.2, 0.3), (0.0, 0.1), (2.0, 1.5), 32)
    claims = {c.id: c for c in camera_model_claims(KINDS, bad, (0.03, 0.018), 1.0)}
    assert not any(c.holds for c in claims.values())
    assert all(c.kind == "diagnostic" for c in claims.values())


def test_v4_rmse_by_method():
    single = pd.DataFrame({"method": ["J-V4", "J-V4", "J", "J"], "err_m": [3.0, 4.0, 1.0, 1.0]})
    assert v4_rmse(single) == (pytest.approx(np.sqrt(12.5)), 1.0)
