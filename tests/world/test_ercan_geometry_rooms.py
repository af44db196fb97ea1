"""Rooms and polygons for the Ercan 2013 camera network: validation, containment, line of sight."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.world.geometry import as_polygon, points_in_polygon, segments_cross_polygon
from fusetrack.world.room import Room, l_shaped_room, square_room


def test_polygon_orientation_and_closing_vertex():
    cw = [[0, 0], [0, 1], [1, 1], [1, 0], [0, 0]]
    v = as_polygon(cw)
    assert v.shape == (4, 2)
    assert 0.5 * np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]) > 0


@pytest.mark.parametrize(
    "bad",
    [
        [[0, 0], [1, 1], [1, 0], [0, 1]],  # bow tie: edges cross
        [[0, 0], [1, 0]],  # too few vertices
        [[0, 0], [1, 0], [2, 0]],  # zero area
        [[0, 0], [1, 0], [np.nan, 1]],
    ],
)
def test_non_simple_or_degenerate_polygon_is_rejected(bad):
    with pytest.raises(ConfigError, match=r"room\.boundary"):
        Room(np.array(bad, float))


def test_static_occluder_outside_room_is_rejected():
    with pytest.raises(ConfigError, match="static_occluders"):
        square_room(10, [[[20, 20], [30, 20], [30, 30]]])


def test_points_in_l_room_and_sight_through_the_reflex_corner():
    room = l_shaped_room(200)
    inside = points_in_polygon(
        np.array([[50, 50], [150, 50], [50, 150], [150, 150]]), room.boundary
    )
    assert inside.tolist() == [True, True, True, False]
    # from the lower-right arm to the upper-left arm the segment leaves the room
    assert room.sight_blocked([190, 60], [60, 190])
    assert not room.sight_blocked([10, 10], [60, 190])
    grid = room.sight_blocked_grid(
        np.array([[190.0, 60.0], [10.0, 10.0]]), np.array([[60.0, 190.0]])
    )
    assert grid[:, 0].tolist() == [True, False]


def test_static_occluder_blocks_and_touching_is_not_crossing():
    room = square_room(100, [[[40, 40], [60, 40], [60, 60], [40, 60]]])
    assert room.sight_blocked([0, 50], [100, 50])
    assert not room.sight_blocked([0, 10], [100, 10])
    assert room.sight_blocked([0, 0], [50, 50])  # a point inside the occluder is hidden
    # a segment that only touches a vertex does not cross
    assert not segments_cross_polygon(
        np.array([0.0, 80.0]), np.array([80.0, 0.0]), room.static_occluders[0]
    )


def test_sample_free_avoids_occluders():
    room = square_room(100, [[[10, 10], [90, 10], [90, 90], [10, 90]]])
    pts = room.sample_free(np.random.default_rng(0), 500)
    assert pts.shape == (500, 2)
    assert room.free(pts).all()


def test_sample_free_draws_what_rejection_from_the_box_draws():
    """Room.sample_free is rejection sampling from the bounding box, candidates x then y per
    round, kept in order: the same points, and the same state of the generator after, as that
    algorithm written plainly; in rooms where one round is enough and where it often is not
    (little free floor left, few points)."""

    def plain(room, rng, n):
        x0, x1, y0, y1 = room.bounding_box
        accept = max(room.free_area / ((x1 - x0) * (y1 - y0)), 1e-3)
        out = np.empty((0, 2))
        while len(out) < n:
            m = int(1.3 * (n - len(out)) / accept) + 8
            cand = np.column_stack([rng.uniform(x0, x1, m), rng.uniform(y0, y1, m)])
            out = np.concatenate([out, cand[room.free(cand)]])
        return out[:n]

    rooms = [l_shaped_room(), square_room(100, [[[1, 1], [99, 1], [99, 99], [1, 99]]])]
    rounds = []
    for room in rooms:
        for n in (1, 2, 50):
            for seed in range(20):
                a, b = np.random.default_rng(seed), np.random.default_rng(seed)
                free_calls = []
                room_free = room.free
                counted = lambda p, calls=free_calls, f=room_free: calls.append(1) or f(p)  # noqa: E731
                object.__setattr__(room, "free", counted)
                try:
                    got = room.sample_free(a, n)
                finally:
                    object.__delattr__(room, "free")
                np.testing.assert_array_equal(got, plain(room, b, n))
                assert a.random() == b.random()
                rounds.append(len(free_calls))
    assert max(rounds) >= 2 and min(rounds) == 1  # both paths were taken


def test_paired_crossing_kernel_matches_numpy_reference():
    """Room.sight_blocked's Numba pass equals segments_cross_polygon (the NumPy reference) per
    polygon: hand-made cases (crossing, touching a vertex, running along an edge, ending on a
    wall) and random segments with broadcast shapes in the L room with a static occluder."""
    from fusetrack.world.occlusion_kernels import segments_cross_edges_paired_kernel

    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    a, b = square, np.roll(square, -1, axis=0)
    starts = np.array([[-1.0, 0.5], [-1.0, -1.0], [-1.0, 0.0], [0.5, 0.5], [-1.0, 0.5]])
    ends = np.array([[2.0, 0.5], [0.0, 0.0], [2.0, 0.0], [0.6, 0.6], [0.0, 0.5]])
    got = segments_cross_edges_paired_kernel(starts, ends, a, b)
    assert got.tolist() == [True, False, False, False, False]
    assert got.tolist() == segments_cross_polygon(starts, ends, square).tolist()

    l_room = l_shaped_room(200.0)
    room = Room(l_room.boundary, (np.array([[120.0, 20], [150, 20], [150, 60], [120, 60]]),))
    rng = np.random.default_rng(5)
    viewers = rng.uniform(-10, 210, (7, 1, 2))
    points = rng.uniform(-10, 210, (1, 50, 2))
    expected = segments_cross_polygon(viewers, points, room.boundary)
    for o in room.static_occluders:
        expected |= segments_cross_polygon(viewers, points, o) | points_in_polygon(points, o)
    got = room.sight_blocked(viewers, points)
    assert got.shape == (7, 50)
    assert np.array_equal(got, expected)
    assert 0 < got.mean() < 1
    assert room.sight_blocked(viewers[0, 0], points[0, 0]).shape == ()
