"""Lee 2009 Sec. 5.2.3: virtual sensors from reader overlaps, coarse position, camera refinement."""

import json

import numpy as np
import pytest

from fusetrack.cli import main
from fusetrack.core.errors import ConfigError
from fusetrack.sensors.rfid_coverage import (
    RfidReader,
    WallCameraPair,
    coarse_position,
    max_virtual_sensors,
    virtual_sensors,
)


def test_counts():
    assert max_virtual_sensors(12, 2) == 78
    three = [RfidReader("a", (4, 4), 2), RfidReader("b", (6, 4), 2), RfidReader("c", (5, 5.7), 2)]
    regions = virtual_sensors(three, (10, 8), 0.02)
    assert len(regions) == 7
    assert frozenset("abc") in regions


def test_coarse_position_and_no_coverage():
    readers = [RfidReader("a", (2, 2), 1.5), RfidReader("b", (4, 2), 1.5)]
    regions = virtual_sensors(readers, (10, 8))
    both = coarse_position(frozenset("ab"), regions)
    assert both == pytest.approx([3.0, 2.0], abs=0.05)
    assert coarse_position(frozenset(), regions) is None  # a tag outside every coverage
    assert coarse_position(frozenset({"zz"}), regions) is None
    with pytest.raises(ConfigError, match="radius"):
        RfidReader("bad", (0, 0), 0.0)


def test_refinement_exact_without_noise():
    cams = WallCameraPair((10, 8), pixel_sigma=0.0)
    p = np.array([6.3, 2.2])
    u = cams.image(p)
    assert cams.refine(np.array([5.0, 3.0]), u) == pytest.approx(p, abs=1e-9)
    rough = cams.refine(np.array([5.0, 3.0]), u, depth_corrected=False)
    assert np.linalg.norm(rough - p) < np.linalg.norm(np.array([5.0, 3.0]) - p)


def test_rfid_experiment_quick(tmp_path):
    assert (
        main(["run", "lee2009-rfid-camera", "--quick", "--runs", "2", "--out", str(tmp_path)]) == 0
    )
    s = json.loads((tmp_path / "summary.json").read_text())
    assert {c["id"] for c in s["claims"]} >= {"C17_three_coverages", "C17_refined_flat"}
