"""The best possible beside Lee 2009's navigation example (navigation_bound): hand-computed
shortest paths, and the escape not beating them."""

import math

import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.experiments.lee2009.navigation_bound import min_steps, shortest_path_length
from fusetrack.world.potential_field import PotentialField, navigate


def test_shortest_path_around_a_disc_on_the_line():
    # d1 = d2 = 2, clearance 1: tangents sqrt 3 each, arc pi - 2 acos(1/2) = pi / 3
    assert shortest_path_length((-2, 0), (2, 0), (0, 0), 1.0) == pytest.approx(
        2 * math.sqrt(3) + math.pi / 3
    )


def test_straight_line_when_it_clears_the_disc_or_the_obstacle_is_a_point():
    assert shortest_path_length((-2, 0), (2, 0), (0, 1.5), 1.0) == pytest.approx(4.0)
    assert shortest_path_length((-2, 0), (2, 0), (0, 0), 0.0) == pytest.approx(4.0)
    # the segment just touches the disc: tangent formula and straight line agree
    assert shortest_path_length((-2, 1), (2, 1), (0, 0), 1.0) == pytest.approx(4.0)
    assert shortest_path_length((-2, 1 - 1e-7), (2, 1 - 1e-7), (0, 0), 1.0) == pytest.approx(4.0)
    with pytest.raises(ConfigError):
        shortest_path_length((0.5, 0), (2, 0), (0, 0), 1.0)


def test_min_steps():
    assert min_steps(6 * math.sqrt(2), math.sqrt(2)) == 6  # rounding does not add a step
    assert min_steps(8.581, math.sqrt(2)) == 7
    with pytest.raises(ConfigError):
        min_steps(1.0, 0.0)


def test_escape_is_not_faster_than_the_shortest_path():
    fld = PotentialField()
    for r in (0.0, 0.3):
        res = navigate(fld, modified=True, escape=True, r_robot=r, r_obstacle=r)
        fewest = min_steps(
            shortest_path_length((12, 12), fld.goal, fld.obstacle, 2 * r), math.sqrt(2)
        )
        assert res.reached_goal_at >= fewest
    # a robot taking 2 s_r T_s per step beats the bound of sqrt 2 steps (6): the check can fail
    fast = navigate(fld, modified=True, escape=True, step=2 * math.sqrt(2))
    assert fast.reached_goal_at == 5
