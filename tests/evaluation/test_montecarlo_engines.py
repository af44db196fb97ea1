import numpy as np
import pandas as pd
import pytest

from fusetrack.core import ConfigError
from fusetrack.evaluation.montecarlo import run_monte_carlo, run_seed


def noisy_mean(config, seed):
    """A pure run: the mean of n draws, with the config echoed into the rows."""
    rng = np.random.default_rng(seed)
    x = rng.normal(config["mu"], 1.0, size=config["n"])
    return [{"stat": "mean", "value": float(x.mean())}, {"stat": "first", "value": float(x[0])}]


CONFIGS = [{"mu": 0.0, "n": 10}, {"mu": 5.0, "n": 100}]


def test_rows_carry_config_run_and_seed():
    df = run_monte_carlo(noisy_mean, CONFIGS, runs=3, seed=7, workers=1, progress=False)
    assert len(df) == 2 * 3 * 2
    assert {"config", "run", "seed", "mu", "n", "stat", "value"} <= set(df.columns)
    assert df.groupby("config")["mu"].first().tolist() == [0.0, 5.0]
    # common random numbers: the same run index gets the same seed in every configuration
    seeds = df.groupby(["config", "run"])["seed"].first().unstack("config")
    assert (seeds[0] == seeds[1]).all()
    assert seeds[0].nunique() == 3


def test_seed_reproduces_and_differs():
    a = run_monte_carlo(noisy_mean, CONFIGS, runs=2, seed=1, workers=1, progress=False)
    b = run_monte_carlo(noisy_mean, CONFIGS, runs=2, seed=1, workers=1, progress=False)
    c = run_monte_carlo(noisy_mean, CONFIGS, runs=2, seed=2, workers=1, progress=False)
    pd.testing.assert_frame_equal(a, b)
    assert not np.allclose(a["value"], c["value"])
    assert run_seed(1, 0) != run_seed(1, 1) != run_seed(2, 0)


def test_engines_and_worker_counts_give_identical_rows():
    ref = run_monte_carlo(noisy_mean, CONFIGS, runs=4, seed=3, workers=1, progress=False)
    pool = run_monte_carlo(noisy_mean, CONFIGS, runs=4, seed=3, workers=2, progress=False)
    pd.testing.assert_frame_equal(ref, pool)
    dask = run_monte_carlo(
        noisy_mean, CONFIGS, runs=4, seed=3, engine="dask", workers=2, progress=False
    )
    pd.testing.assert_frame_equal(ref, dask)


def test_bad_configuration_raises_before_work():
    with pytest.raises(ConfigError, match="runs=0"):
        run_monte_carlo(noisy_mean, CONFIGS, runs=0)
    with pytest.raises(ConfigError, match="engine='spark'"):
        run_monte_carlo(noisy_mean, CONFIGS, runs=1, engine="spark")  # type: ignore[arg-type]
