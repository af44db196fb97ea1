"""One walker model: scripted and random-waypoint walks are the same ``Walk`` value."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.world import Walk, WaypointWalkers, polyline_walk, square_room


def test_polyline_walk_keeps_speed_and_passes_the_corner():
    w = polyline_walk([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]], speed=1.0, fps=2.0)
    assert w.times[1] - w.times[0] == pytest.approx(0.5)
    steps = np.linalg.norm(np.diff(w.xy, axis=0), axis=1)
    straight = np.r_[steps[:5], steps[7:]]  # away from the corner every step is speed / fps
    assert np.allclose(straight, 0.5)
    assert w.xy[6].tolist() == [3.0, 0.0]  # 3 m at 0.5 m a frame: frame 6 is on the corner
    assert np.allclose(w.velocity[1], [1.0, 0.0])


def test_polyline_walk_refuses_a_single_point():
    with pytest.raises(ConfigError, match="waypoints"):
        polyline_walk([[1.0, 2.0]], speed=1.0, fps=15.0)


def test_random_waypoint_walks_are_the_trajectory_as_walks():
    walkers = WaypointWalkers(square_room(20.0))
    traj = walkers.trajectory(3, 10, np.random.default_rng(5))
    walks = walkers.walks(3, 10, 0.5, np.random.default_rng(5))
    assert len(walks) == 3 and all(isinstance(w, Walk) for w in walks)
    for i, w in enumerate(walks):
        assert np.array_equal(w.xy, traj[:, i])
        assert np.allclose(w.times, 0.5 * np.arange(11))
