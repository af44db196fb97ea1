"""Horprasert et al. (1999) background subtraction on constructed pixels (Nott 2009, Sec. 4.1)."""

import numpy as np
import pytest

from fusetrack.core.errors import ShapeError
from fusetrack.perception.video import HorprasertModel, Mog2Subtractor
from fusetrack.perception.video.horprasert import BACKGROUND, FOREGROUND, HIGHLIGHT, SHADOW


@pytest.fixture(scope="module")
def trained():
    rng = np.random.default_rng(0)
    base = rng.uniform(60, 200, (40, 50, 3))
    frames = np.clip(np.rint(base + 2.0 * rng.standard_normal((100, 40, 50, 3))), 0, 255).astype(
        np.uint8
    )
    return base, HorprasertModel.train(frames), rng


def test_constructed_pixels_get_their_class(trained):
    base, model, rng = trained
    img = np.clip(np.rint(base + 2.0 * rng.standard_normal(base.shape)), 0, 255)
    img[0:5] = base[0:5] * 0.6  # shadow: same chromaticity, darker
    img[5:10] = np.clip(base[5:10] * 1.25, 0, 255)  # highlight: same chromaticity, brighter
    img[10:15] = base[10:15][..., ::-1]  # another colour: foreground
    img[15:20] = base[15:20] * 0.2  # far darker than a shadow: foreground (alpha < 0.5)
    cls = model.classify(np.rint(img).astype(np.uint8))
    assert (cls[0:5] == SHADOW).mean() > 0.95
    assert (cls[5:10] == HIGHLIGHT).mean() > 0.9
    diff = np.abs(base[10:15] - base[10:15][..., ::-1]).max(-1) > 30
    assert (cls[10:15][diff] == FOREGROUND).mean() > 0.95
    assert (cls[15:20] == FOREGROUND).all()
    assert (cls[20:] == BACKGROUND).mean() > 0.99


def test_training_frames_are_background_at_the_detection_rate(trained):
    base, model, rng = trained
    fresh = np.clip(np.rint(base + 2.0 * rng.standard_normal((20, *base.shape))), 0, 255).astype(
        np.uint8
    )
    false_fg = np.mean([model.foreground(f).mean() for f in fresh])
    assert false_fg < 0.002  # r = 0.9999 per test, two tests, before morphology


def test_numba_kernel_equals_the_numpy_reference(trained):
    base, model, rng = trained
    img = np.clip(np.rint(base + 30.0 * rng.standard_normal(base.shape)), 0, 255).astype(np.uint8)
    fast, ref = model.foreground(img), model.foreground_reference(img)
    assert (fast != ref).sum() <= 2  # float32 rounding at the threshold


def test_bad_frames_are_refused(trained):
    _, model, _ = trained
    with pytest.raises(ShapeError, match=r"frame\.shape"):
        model.foreground(np.zeros((10, 10, 3), np.uint8))
    with pytest.raises(ShapeError, match=r"frames\.shape"):
        HorprasertModel.train(np.zeros((1, 4, 4, 3)))


def test_mog2_alternative_finds_a_square(trained):
    base, _, rng = trained
    frames = np.clip(np.rint(base + 2.0 * rng.standard_normal((30, *base.shape))), 0, 255).astype(
        np.uint8
    )
    mog = Mog2Subtractor().train(frames)
    img = frames[0].copy()
    img[10:30, 10:30] = (250, 0, 250)
    fg = mog.foreground(img)
    assert fg[12:28, 12:28].mean() > 0.9 and fg[:, 35:].mean() < 0.05
