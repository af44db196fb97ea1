"""RMSE against small hand-computed arrays; NaN handling; time axis."""

import numpy as np
import pytest

from fusetrack.core import ConfigError, ShapeError
from fusetrack.evaluation.metrics import average, position_error, rmse

# T = 2 steps, 2 runs, d = 4 [x, y, vx, vy]; truth is zero so estimates are the errors.
EST = np.array(
    [
        [[3.0, 4.0, 1.0, 0.0], [0.0, 0.0, 0.0, 2.0]],
        [[1.0, 1.0, 0.0, 0.0], [1.0, -1.0, 2.0, 2.0]],
    ]
)
TRUTH = np.zeros((2, 1, 4))


def test_per_axis_over_runs_time_all():
    r = rmse(EST, TRUTH, (0, 1))
    np.testing.assert_allclose(r, [[np.sqrt(4.5), np.sqrt(8.0)], [1.0, 1.0]])
    r = rmse(EST, TRUTH, (0, 1), over="time")  # one per run
    np.testing.assert_allclose(r, [[np.sqrt(5.0), np.sqrt(8.5)], [np.sqrt(0.5), np.sqrt(0.5)]])
    r = rmse(EST, TRUTH, (0, 1), over="all")
    np.testing.assert_allclose(r, [np.sqrt(11 / 4), np.sqrt(18 / 4)])


def test_joint_rmse_of_position_and_velocity():
    # squared position errors: step 0: 25, 0; step 1: 2, 2
    np.testing.assert_allclose(rmse(EST, TRUTH, (0, 1), joint=True), [np.sqrt(12.5), np.sqrt(2.0)])
    assert rmse(EST, TRUTH, (0, 1), joint=True, over="all") == pytest.approx(np.sqrt(29 / 4))
    np.testing.assert_allclose(
        rmse(EST, TRUTH, (0, 1), joint=True, over="time"), [np.sqrt(13.5), np.sqrt(1.0)]
    )
    # squared velocity errors: step 0: 1, 4; step 1: 0, 8
    np.testing.assert_allclose(rmse(EST, TRUTH, (2, 3), joint=True), [np.sqrt(2.5), 2.0])
    np.testing.assert_allclose(position_error(EST, TRUTH, (0, 1)), [[5.0, 0.0], [np.sqrt(2)] * 2])


def test_single_run_and_truth_offset():
    est = np.array([[1.0, 2.0], [2.0, 2.0], [3.0, 5.0]])
    truth = np.array([[0.0, 0.0], [2.0, 2.0], [3.0, 3.0]])
    np.testing.assert_allclose(rmse(est, truth, joint=True), [np.sqrt(5), 0.0, 2.0])
    assert rmse(est, truth, joint=True, over="all") == pytest.approx(np.sqrt(9 / 3))
    np.testing.assert_allclose(rmse(est, truth, over="all"), [np.sqrt(1 / 3), np.sqrt(8 / 3)])


def test_time_axis():
    runs_first = np.swapaxes(EST, 0, 1)  # (R, T, d)
    np.testing.assert_allclose(
        rmse(runs_first, 0.0, (0, 1), joint=True, time_axis=1), rmse(EST, TRUTH, (0, 1), joint=True)
    )
    np.testing.assert_allclose(
        rmse(runs_first, 0.0, over="time", time_axis=1), rmse(EST, TRUTH, over="time")
    )


def test_nan_policies():
    est = EST.copy()
    est[1, 0, 0] = np.nan  # run 0 lost its x at step 1
    p = rmse(est, TRUTH, (0, 1), joint=True)
    assert p[0] == pytest.approx(np.sqrt(12.5)) and np.isnan(p[1])
    assert np.isnan(rmse(est, TRUTH, (0, 1), joint=True, over="all"))
    # omit: the whole sample (step 1, run 0) is dropped from every axis
    p = rmse(est, TRUTH, (0, 1), joint=True, nan_policy="omit")
    np.testing.assert_allclose(p, [np.sqrt(12.5), np.sqrt(2.0)])
    r = rmse(est, TRUTH, (0, 1), nan_policy="omit")
    np.testing.assert_allclose(r[1], [1.0, 1.0])
    assert rmse(est, TRUTH, (0, 1), joint=True, over="all", nan_policy="omit") == pytest.approx(
        np.sqrt(27 / 3)
    )
    # a NaN outside the selected components does not matter
    np.testing.assert_allclose(rmse(est, TRUTH, (2, 3), joint=True), [np.sqrt(2.5), 2.0])
    with pytest.raises(ConfigError, match="estimates"):
        rmse(est, TRUTH, (0, 1), joint=True, nan_policy="raise")
    # every sample missing at a step: NaN even with omit
    est[1] = np.nan
    assert np.isnan(rmse(est, TRUTH, (0, 1), joint=True, nan_policy="omit")[1])


def test_average():
    v = np.array([[1.0, 3.0], [np.nan, 4.0]])
    np.testing.assert_allclose(average(v, nan_policy="omit"), [2.0, 4.0])
    assert np.isnan(average(v)[1])
    assert average(v, over="all", nan_policy="omit") == pytest.approx(8 / 3)
    np.testing.assert_allclose(average(v, over="time", nan_policy="omit"), [1.0, 3.5])


def test_bad_arguments():
    with pytest.raises(ConfigError, match="over"):
        rmse(EST, TRUTH, over="steps")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="nan_policy"):
        rmse(EST, TRUTH, nan_policy="ignore")  # type: ignore[arg-type]
    with pytest.raises(ShapeError, match="truth"):
        rmse(EST, np.zeros((3, 4)))
    with pytest.raises(ConfigError, match="index"):
        rmse(EST, TRUTH, (0, 7), joint=True)
    with pytest.raises(ConfigError, match="time_axis"):
        rmse(EST, TRUTH, time_axis=2)
