"""Track-loss definition on constructed error sequences."""

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.evaluation.metrics import position_error, track_loss_onset, track_loss_rate

# columns are runs, rows are steps; threshold 1.0
E = np.array(
    [
        #  kept  spell3  spell2  nan    end1   twice
        [0.1, 0.1, 2.0, 0.1, 0.1, 5.0],
        [0.2, 2.0, 2.0, np.nan, 0.1, 5.0],
        [0.1, 2.0, 0.5, np.nan, 0.1, 0.1],
        [2.0, 2.0, 0.5, np.nan, 0.1, 5.0],
        [0.1, 0.2, 0.5, 0.1, 0.1, 5.0],
        [0.3, 0.2, 0.5, 0.1, 3.0, 5.0],
    ]
)


def test_k_consecutive_steps():
    onset = track_loss_onset(E, threshold=1.0, k=3)
    np.testing.assert_array_equal(onset, [-1, 1, -1, 1, 5, 3])
    assert track_loss_rate(E, threshold=1.0, k=3) == pytest.approx(4 / 6)


def test_lost_at_end_switch():
    onset = track_loss_onset(E, threshold=1.0, k=3, lost_at_end=False)
    np.testing.assert_array_equal(onset, [-1, 1, -1, 1, -1, 3])
    # k = 1: any bad step loses the run
    np.testing.assert_array_equal(track_loss_onset(E, threshold=1.0, k=1), [3, 1, 0, 1, 5, 0])
    # k longer than the run: only the end rule can fire
    np.testing.assert_array_equal(track_loss_onset(E, threshold=1.0, k=10), [-1, -1, -1, -1, 5, 3])


def test_exactly_threshold_is_kept_and_time_axis():
    e = np.full((4, 1), 1.0)
    assert track_loss_rate(e, threshold=1.0, k=1) == 0.0
    np.testing.assert_array_equal(
        track_loss_onset(E.T, threshold=1.0, k=3, time_axis=1), [-1, 1, -1, 1, 5, 3]
    )


def test_from_estimates():
    truth = np.zeros((5, 2, 4))
    est = truth.copy()
    est[1:3, 1, 0] = 3.0  # run 1 is 3 m off for two steps, then recovers
    err = position_error(est, truth, (0, 1))
    assert track_loss_rate(err, threshold=2.0, k=2) == 0.5
    assert track_loss_rate(err, threshold=2.0, k=3) == 0.0


def test_bad_parameters():
    with pytest.raises(ConfigError, match="k="):
        track_loss_onset(E, threshold=1.0, k=0)
    with pytest.raises(ConfigError, match="threshold"):
        track_loss_rate(E, threshold=-1.0, k=2)
