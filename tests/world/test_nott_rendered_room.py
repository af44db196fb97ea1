"""The rendered room (Nott 2009 stand-in video): exact truth, and the chain's accuracy on it."""

import numpy as np
import pytest

from fusetrack.sensors import NferTagSimulator
from fusetrack.sensors.camera_geometry import ground_homography, plane_homography
from fusetrack.tools.video_tracker import TrackerConfig, VideoRadioTracker
from fusetrack.world.rendered_room import (
    WALL,
    Person,
    RoomRenderer,
    behind_wall_walk,
    crossing_walks,
    single_person_walk,
)


@pytest.fixture(scope="module")
def renderer():
    return RoomRenderer()


def test_truth_pixels_match_the_silhouette(renderer):
    walk = single_person_walk(15.0, 20)
    f = renderer.render([Person(walk)], 10, np.random.default_rng(0))
    rows, cols = np.nonzero(f.full[0])
    assert abs(rows.max() - f.foot[0, 1]) <= 1.0 and abs(rows.min() - f.head[0, 1]) <= 1.5
    assert abs(cols[rows >= rows.max() - 2].mean() - f.foot[0, 0]) < 3
    assert f.image.shape == (480, 640, 3) and f.image.dtype == np.uint8


def test_wall_hides_the_walker(renderer):
    wall = RoomRenderer(wall=WALL)
    walk = behind_wall_walk(15.0, 90)
    rng = np.random.default_rng(1)
    vis = [
        (f.visible[0].sum() / f.full[0].sum())
        for f in (wall.render([Person(walk)], k, rng) for k in (0, 36, 89))
    ]
    assert vis[1] == 0.0 and vis[0] > 0.95 and vis[2] > 0.95


def _chain_errors(renderer, people, n_frames, seed=0, first=0):
    rng = np.random.default_rng(seed)
    P = renderer.camera.P
    trk = VideoRadioTracker(
        TrackerConfig(
            foot_homography=ground_homography(P), head_homography=plane_homography(P, 1.75)
        )
    )
    trk.train_background(renderer.empty_frames(40, rng))
    frames = [renderer.render(people, k, rng) for k in range(first, n_frames)]
    tag = NferTagSimulator("field", sigma=(0.1, 0.1), quantum=0.098, field_seed=seed)
    idx = np.arange(first, n_frames, 3)
    radio = np.column_stack([people[0].walk.times[idx], tag.simulate(people[0].walk.xy[idx], rng)])
    others = None
    if len(people) > 1:
        o = tag.simulate(people[1].walk.xy[idx], rng)
        others = np.column_stack([people[1].walk.times[idx], o, np.ones(len(idx))])
    res = list(trk.run(((f.index, f.time, f.image) for f in frames), radio, others))
    return frames, res


def test_chain_on_rendered_video_single_person(renderer):
    people = [Person(single_person_walk(15.0, 30), separate_hand=True)]
    frames, res = _chain_errors(renderer, people, 30)
    foot = np.array(
        [np.hypot(r.foot_u - f.foot[0, 0], r.foot_v - f.foot[0, 1]) for r, f in zip(res, frames)]
    )
    err = np.array([np.hypot(r.x - f.xy[0, 0], r.y - f.xy[0, 1]) for r, f in zip(res, frames)])
    assert np.median(foot) < 1.5  # a broken BGS/blob stage gives tens of pixels
    assert np.sqrt(np.mean(err[8:] ** 2)) < 0.06  # a broken filter is at the tag's ~0.5 m
    assert not any(r.occluded for r in res)


def test_chain_detects_the_crossing(renderer):
    a, b = crossing_walks(15.0, 70)
    people = [Person(b, shirt=(40, 160, 60), trousers=(70, 70, 70)), Person(a)]
    frames, res = _chain_errors(renderer, people, 62, first=30)
    truth = np.array([f.visible[0].sum() / f.full[0].sum() < 0.8 for f in frames])
    flagged = np.array([r.occluded for r in res])
    assert truth.any() and (flagged & truth).sum() / truth.sum() >= 0.9
    err = np.array([np.hypot(r.x - f.xy[0, 0], r.y - f.xy[0, 1]) for r, f in zip(res, frames)])
    assert err[flagged].max() < 0.5
