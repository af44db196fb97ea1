"""The synthetic head-video renderer: exact ground truth, manoeuvre timelines, occlusion, ego-motion."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.world.head_video import Actor, Scene, Sprite, keyframe_trajectory, render

PLAIN = Scene(height=80, width=100, clutter=0, noise=0.0, contrast=0.0)
FLAT = Sprite(axes=(8.0, 10.0), colour=(250, 20, 20), hair=None, texture=0.0)


def test_keyframes_integrate_exactly():
    # v = 1, 2, 3, 3 (linear 1 -> 3 over frames 0..2); x_{k+1} = x_k + (v_k + v_{k+1}) / 2
    tr = keyframe_trajectory([0.0, 5.0, 9.0, 9.0], [(0, 1.0, 0.0), (2, 3.0, 0.0)], 4)
    np.testing.assert_allclose(tr[:, 2], [1, 2, 3, 3])
    np.testing.assert_allclose(tr[:, 0], [0, 1.5, 4.0, 7.0])
    np.testing.assert_allclose(tr[:, 1], 5.0)
    np.testing.assert_allclose(tr[:, 3], 0.0)


def test_keyframes_need_increasing_frames_and_rng_for_jitter():
    with pytest.raises(ConfigError, match="keyframes"):
        keyframe_trajectory([0, 0, 0, 0], [(3, 0, 0), (1, 0, 0)], 5)
    with pytest.raises(ConfigError, match="rng"):
        keyframe_trajectory([0, 0, 0, 0], [], 5, jitter=0.1)


def _red_centroid(frame):
    mask = (frame[..., 0] > 150) & (frame[..., 1] < 100)
    rows, cols = np.nonzero(mask)
    return np.array([cols.mean(), rows.mean()])


def test_rendered_target_sits_at_its_truth():
    tr = keyframe_trajectory([30.3, 40.7, 2.2, -0.6], [], 12)
    seq = render(PLAIN, Actor(FLAT, tr), np.random.default_rng(0))
    assert seq.frames.shape == (12, 80, 100, 3) and seq.frames.dtype == np.uint8
    for k in (0, 5, 11):
        np.testing.assert_allclose(_red_centroid(seq.frames[k]), tr[k, :2], atol=0.15)
    np.testing.assert_allclose(seq.half_size, 8.0)


def test_scale_grows_the_sprite():
    tr = keyframe_trajectory([50, 40, 0, 0], [], 3)
    seq = render(PLAIN, Actor(FLAT, tr, np.array([1.0, 1.5, 2.0])), np.random.default_rng(0))
    areas = [np.count_nonzero(seq.frames[k, ..., 0] > 150) for k in range(3)]
    np.testing.assert_allclose(np.array(areas) / areas[0], [1, 2.25, 4], rtol=0.06)
    np.testing.assert_allclose(seq.half_size, [8, 12, 16])


def test_actor_in_front_occludes_the_target():
    tr = keyframe_trajectory([50, 40, 0, 0], [], 2)
    blue = Sprite(axes=(12.0, 12.0), colour=(20, 20, 250), hair=None, texture=0.0)
    seq = render(PLAIN, Actor(FLAT, tr), np.random.default_rng(0), [Actor(blue, tr, in_front=True)])
    assert np.count_nonzero(seq.frames[0, ..., 0] > 150) == 0  # hidden
    seq = render(PLAIN, Actor(FLAT, tr), np.random.default_rng(0), [Actor(blue, tr)])
    assert np.count_nonzero(seq.frames[0, ..., 0] > 150) > 200  # drawn over the other


def test_ego_motion_shifts_the_background():
    ego = np.array([[0.0, 0.0], [7.0, -3.0]])
    scene = Scene(height=60, width=70, clutter=30, noise=0.0, ego_motion=ego)
    tr = np.full((2, 4), -100.0)  # target off-screen
    seq = render(scene, Actor(FLAT, tr), np.random.default_rng(1))
    f0, f1 = seq.frames[0].astype(int), seq.frames[1].astype(int)
    np.testing.assert_array_equal(f1[3:, : 70 - 7], f0[: 60 - 3, 7:])


def test_illumination_gain_and_bad_inputs():
    tr = keyframe_trajectory([50, 40, 0, 0], [], 2)
    seq = render(
        Scene(height=40, width=40, clutter=0, noise=0.0, gain=np.array([1.0, 0.5])),
        Actor(FLAT, tr[:, :]),
        np.random.default_rng(0),
    )
    ratio = seq.frames[1].astype(float).mean() / seq.frames[0].astype(float).mean()
    assert ratio == pytest.approx(0.5, abs=0.02)
    with pytest.raises(ConfigError, match="ego_motion"):
        render(Scene(ego_motion=np.full((2, 2), 500.0)), Actor(FLAT, tr), np.random.default_rng(0))
    with pytest.raises(ConfigError, match="scale"):
        render(PLAIN, Actor(FLAT, tr, np.ones(3)), np.random.default_rng(0))
