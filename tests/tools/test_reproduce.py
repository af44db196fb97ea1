"""``fusetrack reproduce``: the run path in a loop, one experiment after the other, into OUT/NAME."""

import json

from fusetrack.cli import main


def test_reproduce_quick_into_a_folder(tmp_path, capsys):
    code = main(
        ["reproduce", "lee2009-network-traffic", "--quick", "--out", str(tmp_path), "--no-progress"]
    )
    assert code == 0
    summary = json.loads((tmp_path / "lee2009-network-traffic" / "summary.json").read_text())
    assert summary["seed"] == 0 and summary["quick"] is True
    assert all(c["kind"] == "paper" for c in summary["claims"])
    err = capsys.readouterr().err
    assert "[1/1] lee2009-network-traffic ->" in err and "paper claims hold" in err


def test_reproduce_needs_names_or_all(tmp_path, capsys):
    assert main(["reproduce", "--out", str(tmp_path)]) == 2
    assert main(["reproduce", "demo", "--all", "--out", str(tmp_path)]) == 2
    assert main(["reproduce", "no-such", "--out", str(tmp_path)]) == 2
    assert "no-such" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())  # nothing ran
