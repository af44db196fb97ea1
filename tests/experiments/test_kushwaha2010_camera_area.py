"""kushwaha2010-cameras-area (spec H19): the scaled target and the T2/T3 crossover."""

import math

import numpy as np
import pandas as pd

from fusetrack.experiments.kushwaha2010.camera_area import crossover, run_once, scaled_target


def test_crossover_interpolates_in_log_fraction():
    f = pd.Series([0.001, 0.01, 0.1], index=[0.25, 0.5, 1.0])
    # T3 - T2: +1 (T2 better) at 0.1 %, -1 at 1 %: half-way in log fraction, 10**-2.5
    gap = pd.Series([1.0, -1.0, -2.0], index=[0.25, 0.5, 1.0])
    assert math.isclose(crossover(f, gap), 10**-2.5)
    assert math.isnan(crossover(f, -gap.abs()))  # T3 better everywhere: no crossover
    assert math.isnan(crossover(f, gap.abs()))  # T2 better everywhere


def test_scaled_target_keeps_the_path_and_shrinks_the_image():
    assert scaled_target(0.5).semi_axes == (0.15, 0.1, 0.2)
    cfg = {"steps": 3, "n_particles": 40, "n_particles_2d": 20}
    small = pd.DataFrame(run_once({**cfg, "scale": 0.5}, 5))
    large = pd.DataFrame(run_once({**cfg, "scale": 1.0}, 5))
    assert set(small.tracker) == {"T0", "T2", "T3"}
    assert np.all(np.isfinite(small.err3d))
    s, g = small[small.tracker == "T0"], large[large.tracker == "T0"]
    ratio = s.pixel_fraction.to_numpy() / g.pixel_fraction.to_numpy()
    assert np.all((ratio > 0.15) & (ratio < 0.4))  # area x 0.25, up to pixel rounding
