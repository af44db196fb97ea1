"""A scan of 5000 false alarms through the MHT tracker: it completes (each false alarm is a
tentative family with one root leaf, dropped by M-of-N) and confirms no extra track."""

from __future__ import annotations

import numpy as np
from _tracking_scenarios import CLUTTER_RATE, MOTION, POS, SIDE, WIDE, with_flood

from fusetrack.association import TrackOrientedMHT
from fusetrack.filters import KalmanFilter
from fusetrack.tracking import (
    InverseMeasurementPrior,
    MHTTracker,
    MissedCountDeleter,
    MofNInitiator,
)


def test_a_scan_of_5000_false_alarms_through_the_mht():
    tr = MHTTracker(
        KalmanFilter(MOTION, [POS]), [POS], TrackOrientedMHT(n_scan=2),
        MofNInitiator(3, 4, InverseMeasurementPrior([POS], WIDE)), MissedCountDeleter(3),
        p_detect=0.9, clutter_density=CLUTTER_RATE / SIDE**2, gate_probability=0.999,
    )  # fmt: skip
    tracks, state = tr.run_with_state(with_flood(), np.random.default_rng(0), order="reorder")
    assert len(tracks) == 2 and all(t.times[-1] == 9 for t in tracks)
    assert state.stats.births >= 5000 and state.stats.confirmed == 2
    assert len(state.tracks) <= 10 and len(state.hypotheses.leaves) <= 10 * 20
    assert set(state.leaf_beliefs) == {leaf.id for leaf in state.hypotheses.leaves}
