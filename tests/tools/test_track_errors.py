"""``fusetrack track`` refuses a bad scene before any work, naming the field, the value and what
is valid: a missing file, a channel count that does not match the array, clocks that disagree,
an unknown sensor kind, a recording that cannot give the sensor's readings."""

from __future__ import annotations

import copy
from pathlib import Path

import pandas as pd
import pytest
import yaml

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.tools import load_scene
from fusetrack.tools.track_scene import track_scene

SAMPLE = Path(__file__).resolve().parents[2] / "examples" / "sample"
BASE = yaml.safe_load((SAMPLE / "scene.yaml").read_text())


def scene_with(tmp_path: Path, change) -> Path:
    """The sample scene, with absolute paths, changed by ``change(data)``, written in tmp_path."""
    data = copy.deepcopy(BASE)
    data["truth"] = str(SAMPLE / data["truth"])
    for s in data["sensors"]:
        rec = s["recording"]
        rec["path"] = str(SAMPLE / rec["path"])
        if "calibration" in rec:
            rec["calibration"] = str(SAMPLE / rec["calibration"])
    change(data)
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def refused(tmp_path: Path, change, *fragments: str) -> None:
    out = tmp_path / "out"
    with pytest.raises(ConfigError) as err:
        track_scene(scene_with(tmp_path, change), out, progress=False, quick=True)
    for f in fragments:
        assert f in str(err.value)
    assert not out.exists()  # nothing written


def test_a_missing_recording_names_the_sensor_and_the_file(tmp_path):
    def change(d):
        d["sensors"][2]["recording"]["path"] = str(tmp_path / "nope.csv")

    refused(tmp_path, change, "sensors[2].recording.path=", "nope.csv", "an existing file")


def test_a_channel_count_that_does_not_match_the_array(tmp_path):
    def change(d):
        d["sensors"][0]["recording"]["microphones"] = d["sensors"][0]["recording"]["microphones"][
            :3
        ]

    refused(tmp_path, change, "sensors[0].recording.microphones=", "3 microphones", "4 channels")


def test_unsynchronised_clocks_beyond_the_tolerance(tmp_path):
    def change(d):
        d["sensors"][2]["recording"]["offset"] = 1.7e9  # Unix seconds beside a video from 0 s

    refused(tmp_path, change, "sensors[2].recording.offset=1700000000.0", "clock_tolerance=1 s")


def test_clocks_within_the_tolerance_are_accepted(tmp_path):
    def change(d):
        d["sensors"][2]["recording"]["offset"] = 5.9  # tag 7.4..12.2 s: 0.9 s after the rest

    scene, _, base = load_scene(scene_with(tmp_path, change))
    from fusetrack.tools.track_scene import _check

    assert [s.span[0] for s in _check(scene, base)][2] == pytest.approx(7.4)


def test_an_unknown_sensor_kind_lists_the_valid_ones(tmp_path):
    def change(d):
        d["sensors"][0]["kind"] = "sonar"

    refused(tmp_path, change, "sensors[0].kind='sonar'", "'bearing'", "'position_fix'")


def test_a_recording_that_cannot_give_the_sensors_readings(tmp_path):
    def change(d):
        d["sensors"][0]["kind"] = "position_fix"
        d["sensors"][0]["cov"] = [[1, 0], [0, 1]]

    refused(tmp_path, change, "sensors[0]", "a wav recording gives bearing readings")


def test_a_table_without_the_kinds_columns(tmp_path):
    pd.DataFrame({"time": [1.0], "x": [1.0]}).to_csv(tmp_path / "fix.csv", index=False)

    def change(d):
        d["sensors"][2]["recording"] = {"path": str(tmp_path / "fix.csv")}

    refused(
        tmp_path,
        change,
        "sensors[2].recording.path=",
        "columns ['time', 'x', 'y']",
        "missing ['y']",
    )


def test_the_command_line_says_the_error_and_exits_2(tmp_path, capsys):
    def change(d):
        d["tracker"]["filter"] = "kf"

    out = tmp_path / "out"
    assert main(["track", "--config", str(scene_with(tmp_path, change)), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "tracker.filter='kf' is invalid" in err and "'ekf'" in err
    assert not out.exists()
    assert main(["track", "--config", str(tmp_path / "none.yaml"), "--out", str(out)]) == 2
    assert "an existing scene YAML file" in capsys.readouterr().err


def test_a_value_that_is_not_a_number_names_its_row(tmp_path):
    pd.DataFrame({"time": [1.0, 2.0], "x": [1.0, "far"], "y": [1.0, 2.0]}).to_csv(
        tmp_path / "fix.csv", index=False
    )

    def change(d):
        d["sensors"][2]["recording"] = {"path": str(tmp_path / "fix.csv")}

    refused(tmp_path, change, "column 'x' at data row 2='far'", "a finite number")
