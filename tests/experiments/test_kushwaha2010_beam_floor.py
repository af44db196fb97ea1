"""The beam grid's floor beside Fig. 11 (issue 19 item 3): no estimate restricted to the 36 beams,
10 degrees apart, can err less than the distance to the nearest beam."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.experiments.kushwaha2010.beamformer import beam_grid_floor, doa_trial


@pytest.mark.parametrize(
    ("angle_deg", "floor_deg"),
    [(0.0, 0.0), (5.0, 5.0), (12.5, 2.5), (357.0, 3.0), (-4.0, 4.0), (-175.0, 5.0), (181.0, 1.0)],
)
def test_floor_is_the_distance_to_the_nearest_beam_across_the_wrap(angle_deg, floor_deg):
    assert np.rad2deg(beam_grid_floor(np.deg2rad(angle_deg))) == pytest.approx(floor_deg, abs=1e-9)


def test_no_trial_beats_the_floor():
    rng = np.random.default_rng(3)
    for angle in rng.uniform(-np.pi, np.pi, 4):
        assert doa_trial(25 * 0.3048, angle, rng) >= beam_grid_floor(angle) - 1e-12
