"""The radio tag of Nott 2009: Table 5.1 and the simulated NFER tag."""

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.experiments.nott2009.radio import TABLE_5_1_RFID, TABLE_5_1_TRUTH, table_summary
from fusetrack.sensors import NferTagSimulator, fit_position_fix


def test_table_5_1_recomputed():
    s = table_summary()
    assert s["mean"] == pytest.approx(0.458, abs=5e-4)
    assert s["std_sample"] == pytest.approx(0.273, abs=5e-4)
    assert s["std_population"] == pytest.approx(0.249, abs=5e-4)
    fit = fit_position_fix(TABLE_5_1_TRUTH, TABLE_5_1_RFID)
    assert np.allclose(fit.cov, [[0.2861, 0.0264], [0.0264, 0.0330]], atol=1e-4)


def test_white_model_statistics_and_dropouts():
    tag = NferTagSimulator("white", sigma=(0.6, 0.4), dropout=0.2)
    p = np.zeros((20000, 2))
    z = tag.simulate(p, np.random.default_rng(0))
    lost = np.isnan(z).any(1)
    assert lost.mean() == pytest.approx(0.2, abs=0.02)
    assert np.std(z[~lost], axis=0) == pytest.approx([0.6, 0.4], rel=0.03)


def test_field_model_is_spatially_correlated_and_quantised():
    tag = NferTagSimulator("field", sigma=(0.0, 0.0), quantum=0.098)
    near = tag.bias(np.array([[3.0, 4.0], [3.1, 4.0]]))
    far = tag.bias(np.array([[3.0, 4.0], [13.0, 4.0]]))
    assert np.abs(near[0] - near[1]).max() < 0.1 < np.abs(far[0] - far[1]).max() + 0.1
    z = tag.simulate(np.array([[3.0, 4.0]]), np.random.default_rng(0))
    assert np.allclose(z / 0.098, np.round(z / 0.098))


def test_bad_settings():
    with pytest.raises(ConfigError, match="model"):
        NferTagSimulator("gauss")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="sigma"):
        NferTagSimulator("white", sigma=(0.6,))  # type: ignore[arg-type]
