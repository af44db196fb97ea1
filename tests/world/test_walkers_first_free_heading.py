"""The Numba first-free-heading search of the walkers equals its NumPy reference."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.world import walkers as walkers_module
from fusetrack.world.room import Room
from fusetrack.world.walkers import (
    WaypointWalkers,
    first_free_heading_kernel,
    first_free_heading_reference,
)


@pytest.mark.parametrize("n", [2, 7, 60])
def test_kernel_equals_reference_on_crowded_random_steps(n):
    rng = np.random.default_rng(n)
    pos = rng.uniform(0, 12, (n, 2))  # crowded: many candidate steps are blocked
    cand = pos[:, None, :] + rng.normal(0, 1.5, (n, 25, 2))
    ok = rng.random((n, 25)) < 0.7
    fast = first_free_heading_kernel(cand, ok, pos, 3.33**2)
    ref = first_free_heading_reference(cand, ok, pos, 3.33**2)
    assert np.array_equal(fast, ref)
    assert (fast == -1).any() or n < 60  # the crowded case has walkers that must stand still


def test_hand_case():
    pos = np.array([[0.0, 0.0], [1.0, 0.0]])
    # walker 0 tries (1.1, 0) (too close to walker 1), then (0, 1.5) (free); walker 1 has no free step
    cand = np.array([[[1.1, 0.0], [0.0, 1.5]], [[0.5, 0.0], [0.0, 0.0]]])
    ok = np.array([[True, True], [True, False]])
    assert first_free_heading_kernel(cand, ok, pos, 1.0).tolist() == [1, -1]


def test_trajectories_identical_to_the_reference_search(monkeypatch):
    room = Room(
        np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]]),
        (np.array([[15.0, 15.0], [25.0, 15.0], [25.0, 25.0], [15.0, 25.0]]),),
    )
    walkers = WaypointWalkers(room)
    fast = walkers.trajectory(80, 60, np.random.default_rng(3))
    monkeypatch.setattr(
        walkers_module,
        "first_free_heading_kernel",
        lambda cand, ok, pos, g2: first_free_heading_reference(cand, ok, pos, g2),
    )
    ref = walkers.trajectory(80, 60, np.random.default_rng(3))
    assert np.array_equal(fast, ref)


def test_a_dense_crowd_does_not_jam_for_good():
    """50 walkers in a 40 x 40 room (a third of the floor covered). With turns only up to +-90
    degrees and no new destination when boxed in, 85-91% of them stood still for good after 300
    steps (seeds 0-2); turning further round and re-planning keeps the crowd moving."""
    room = Room(np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]]))
    for seed in range(3):
        tr = WaypointWalkers(room).trajectory(50, 400, np.random.default_rng(seed))
        moved = np.hypot(*np.diff(tr, axis=0).transpose(2, 0, 1))
        assert np.mean(moved[-100:] < 0.05) < 0.4
