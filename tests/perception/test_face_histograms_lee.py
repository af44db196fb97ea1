"""Lee 2009 Sec. 5.2.1: Bhattacharyya coefficient, view count, walking direction (C16)."""

import json
import math

import numpy as np
import pytest

from fusetrack.cli import main
from fusetrack.core.errors import ConfigError, ShapeError
from fusetrack.perception.face_histograms import (
    CAMERA_VIEWS,
    COMPASS,
    apparent_motion,
    bhattacharyya,
    colour_histogram,
    n_views,
    synthetic_face,
    walking_direction,
)


def test_bhattacharyya_bounds():
    p = np.array([0.2, 0.3, 0.5, 0.0])
    assert bhattacharyya(p, p) == pytest.approx(1.0)
    assert bhattacharyya(p, np.array([0, 0, 0, 1.0])) == 0.0
    with pytest.raises(ShapeError):
        bhattacharyya(p, p[:3])


def test_histogram_and_views():
    img = synthetic_face(0.0, (0.8, 0.6, 0.5), (0.1, 0.1, 0.1), np.random.default_rng(0))
    h = colour_histogram(img, bins=8)
    assert h.shape == (512,) and h.sum() == pytest.approx(1.0)
    assert n_views(math.pi / 4) == 5  # Eq. 5.6: pi / dtheta + 1
    with pytest.raises(ConfigError):
        n_views(0.0)
    with pytest.raises(ShapeError):
        colour_histogram(np.zeros((4, 4)))


def test_walking_direction_text_examples():
    north = {c: apparent_motion(v, COMPASS["N"]) for c, v in CAMERA_VIEWS.items()}
    assert north == {"1": (-1, 0), "2": (-1, 0), "3": (0, -1), "4": (1, 0), "5": (0, 1)}
    ne = {c: apparent_motion(v, COMPASS["NE"]) for c, v in CAMERA_VIEWS.items()}
    assert ne == {"1": (-1, -1), "2": (-1, -1), "3": (1, -1), "4": (1, 1), "5": (-1, 1)}
    for d in COMPASS:
        obs = {c: apparent_motion(v, COMPASS[d]) for c, v in CAMERA_VIEWS.items()}
        assert walking_direction(obs) == d
    with pytest.raises(ConfigError):
        walking_direction({"9": (1, 1)})


def test_face_experiment_quick(tmp_path):
    assert (
        main(["run", "lee2009-face-matching", "--quick", "--runs", "1", "--out", str(tmp_path)])
        == 0
    )
    s = json.loads((tmp_path / "summary.json").read_text())
    ids = {c["id"] for c in s["claims"]}
    assert "C16_walking_direction" in ids and "C16_rho_bounds" not in ids  # it held by construction
