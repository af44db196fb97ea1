"""Lee 2009 Sec. 5.2.2: the robot collides at step 4 with the standard field and not with the modified one."""

import json
import math

import numpy as np
import pytest

from fusetrack.cli import main
from fusetrack.core.errors import ConfigError
from fusetrack.world.potential_field import PotentialField, navigate


def test_standard_field_collides_at_step_4():
    res = navigate(PotentialField())
    assert res.collided_at == 4
    assert res.path[:4].tolist() == [[12, 12], [11, 11], [10, 10], [9, 9]]


def test_modified_field_oscillates_and_escape_reaches_goal():
    fld = PotentialField()
    mod = navigate(fld, modified=True, max_steps=10)
    assert mod.collided_at is None and mod.oscillation_at == 4
    assert {tuple(p) for p in mod.path.round(9).tolist()[3:]} == {(9.0, 9.0), (10.0, 10.0)}
    esc = navigate(fld, modified=True, escape=True)
    assert esc.collided_at is None and esc.reached_goal_at is not None
    assert fld.zero_force_distance() == pytest.approx(1.2844, abs=1e-4)
    u = np.ones(2) / math.sqrt(2)
    assert float(fld.total(np.array([9.0, 9.0])) @ u) == pytest.approx(-1.21, abs=0.01)
    with pytest.raises(ConfigError):
        navigate(fld, step=0.0)


def test_robot_experiment_end_to_end(tmp_path):
    assert main(["run", "lee2009-robot-navigation", "--quick", "--out", str(tmp_path)]) == 0
    s = json.loads((tmp_path / "summary.json").read_text())
    assert all(c["holds"] for c in s["claims"])
    assert "BP_goal_not_before_shortest_path" in {c["id"] for c in s["claims"]}
    assert "No Cramér-Rao bound applies here" in (tmp_path / "report.md").read_text()
    assert (tmp_path / "robot_paths.png").exists()
