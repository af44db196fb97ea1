"""Algorithm 7's demo (Zhai 2007, Figs 55-56): what "inside the cells" means and the per-seed
verdicts the claims count."""

import numpy as np
import pandas as pd

from fusetrack.experiments.zhai2007.alg7_demo import MODELS, inside_cells, seed_verdicts


def test_inside_cells_is_inside_a_cells_box():
    centres = np.array([[0.0, 0.0, 9.0], [2.0, 0.0, 9.0]])  # extra columns are not position
    delta = np.array([1.0, 0.5])
    assert inside_cells(np.array([0.5, 0.25]), centres, delta)  # on the first box's corner
    assert inside_cells(np.array([2.4, -0.2]), centres, delta)
    assert not inside_cells(np.array([1.0, 0.0]), centres, delta)  # between the boxes
    assert not inside_cells(np.array([0.0, 0.3]), centres, delta)  # above (Delta_y / 2 = 0.25)


def _row(truth_in, z_in, n, dist):
    row = {}
    for k, m in enumerate(MODELS):
        row |= {f"truth in {m}": truth_in[k], f"z in {m}": z_in[k], f"n {m}": n[k]}
        row[f"dist {m}"] = dist[k]
    return row


def test_seed_verdicts_follow_the_thesis_statements():
    t = pd.DataFrame(
        [
            # the thesis's picture: outside CV, covered by CA; CA fewest and closest
            _row([0, 0, 0, 1], [0, 0, 1, 0], [50, 20, 20, 10], [2.0, 3.0, 3.0, 0.5]),
            # the measurement in a CV cell; CA ties with CW; CW closer than CA
            _row([0, 0, 0, 1], [1, 0, 0, 1], [50, 20, 15, 15], [2.0, 3.0, 0.4, 0.5]),
        ]
    ).astype({f"{w} in {m}": bool for w in ("truth", "z") for m in MODELS})
    v = seed_verdicts(t)
    assert v["outside CV, inside another"].tolist() == [True, False]
    assert v["CA fewest"].tolist() == [True, False]
    assert v["CA fewer than CV"].tolist() == [True, True]
    assert v["CA closest"].tolist() == [True, False]
