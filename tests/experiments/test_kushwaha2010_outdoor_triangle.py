"""kushwaha2010-outdoor-triangle (spec E6/H17): the 9.144 m triangle and source 2's placement."""

import numpy as np

from fusetrack.experiments.kushwaha2010.outdoor_triangle import NODES, second_position


def test_triangle_is_15_ft_equilateral_and_source_2_at_the_separation():
    sides = [np.hypot(*(NODES[i] - NODES[(i + 1) % 3])) for i in range(3)]
    np.testing.assert_allclose(sides, 9.144)
    centroid = NODES.mean(axis=0)
    rng = np.random.default_rng(0)
    for sep in (0.5, 2.0, 8.0):
        p = second_position(sep, rng)
        assert abs(np.hypot(*(p - centroid)) - sep) < 1e-9
        assert np.min(np.hypot(*(NODES - p).T)) >= 1.0
