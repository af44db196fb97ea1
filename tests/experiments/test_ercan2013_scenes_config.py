"""User scenes for the Ercan 2013 tracker and selection: YAML files and the errors bad ones give."""

import json

import numpy as np
import pytest
import yaml

from fusetrack.cli import main
from fusetrack.core.errors import ConfigError
from fusetrack.experiments.ercan2013.scenes import (
    l_scene,
    lab_scene,
    load_scene,
    scene_from_mapping,
    square_scene,
)

GOOD = {
    "room": [[0, 0], [100, 0], [100, 60], [0, 60]],
    "static_occluders": [[[40, 20], [50, 20], [50, 30], [40, 30]]],
    "cameras": [
        {"position": [0.5, 0.5], "yaw": 30},
        {"position": [99.5, 59.5], "yaw": 210, "fov": 60},
    ],
}


def test_builtin_scenes_are_valid():
    for scene in (square_scene(True), square_scene(False), l_scene(), lab_scene()):
        assert len(scene.fixed_order) <= len(scene.cameras)
    assert len(l_scene().cameras) == 12 and len(lab_scene().cameras) == 16


def test_scene_from_mapping_and_yaml(tmp_path):
    s = scene_from_mapping(GOOD)
    assert len(s.cameras) == 2 and np.degrees(s.cameras.fovs[1]) == pytest.approx(60)
    path = tmp_path / "room.yaml"
    path.write_text(yaml.safe_dump(GOOD))
    assert load_scene(path).room.static_occluders[0].shape == (4, 2)


@pytest.mark.parametrize(
    "change,match",
    [
        ({"cameras": [{"position": [150, 30], "yaw": 180}]}, "camera position"),  # behind the wall
        (
            {"cameras": [{"position": [0.5, 0.5], "yaw": 225}]},
            "camera view",
        ),  # looks at the wall only
        ({"room": [[0, 0], [100, 60], [100, 0], [0, 60]]}, "room.boundary"),  # not simple
        ({"cameras": []}, "config.cameras"),
        ({"cameras": [{"position": [1, 1]}]}, "cameras"),
    ],
)
def test_bad_scenes_give_clear_errors(change, match):
    with pytest.raises(ConfigError, match=match):
        scene_from_mapping({**GOOD, **change})


def test_missing_or_broken_file(tmp_path):
    with pytest.raises(ConfigError, match="existing YAML file"):
        load_scene(tmp_path / "nope.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("room: [[0, 0], [1")
    with pytest.raises(ConfigError, match="valid YAML"):
        load_scene(bad)


def test_selection_runs_on_a_user_room(tmp_path, monkeypatch):
    monkeypatch.setenv("FUSETRACK_SMOKE", "1")
    cfg = tmp_path / "room.yaml"
    cfg.write_text(
        yaml.safe_dump(
            {**GOOD, "cameras": GOOD["cameras"] + [{"position": [99.5, 0.5], "yaw": 150}]}
        )
    )
    out = tmp_path / "out"
    code = main(["run", "ercan2013-selection", "--config", str(cfg), "--quick", "--runs", "1", "--workers", "1",
                 "--no-progress", "--out", str(out)])  # fmt: skip
    assert code == 0
    assert json.loads((out / "summary.json").read_text())["claims"]
    assert (out / "fig11_room.png").exists()
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({**GOOD, "cameras": [{"position": [150, 30], "yaw": 180}]}))
    assert (
        main(["run", "ercan2013-selection", "--config", str(bad), "--out", str(tmp_path / "o2")])
        == 2
    )
