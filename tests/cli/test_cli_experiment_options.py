"""`fusetrack run NAME --set KEY=VALUE` / `--measurements`: options reach the experiment via ctx.extra."""

import json

from fusetrack.cli import _extra_options, build_parser, main


def _extra(argv):
    return _extra_options(build_parser().parse_args(argv))


def test_set_and_measurements_fill_extra():
    argv = [
        "run",
        "x",
        "--out",
        "o",
        "--set",
        "a=1",
        "--set",
        " b = two ",
        "--measurements",
        "audio",
    ]
    assert _extra(argv) == {"a": "1", "b": "two", "measurements": "audio"}
    assert (
        _extra(["run", "x", "--out", "o"]) == {}
    )  # backwards compatible: nothing given, nothing set


def test_bad_set_and_bad_value_are_clear_errors(tmp_path, capsys):
    assert (
        main(["run", "lee2009-projected-planes", "--out", str(tmp_path), "--set", "novalue"]) == 2
    )
    assert "KEY=VALUE" in capsys.readouterr().err
    argv = ["run", "lee2009-projected-planes", "--out", str(tmp_path), "--measurements", "radar"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "measurements" in err and "radar" in err and "audio" in err
    argv = ["run", "lee2009-projected-planes", "--out", str(tmp_path), "--set", "colour=red"]
    assert main(argv) == 2
    assert "colour" in capsys.readouterr().err


def test_projected_planes_audio_form(tmp_path):
    """The issue's form; `--set measurements=audio` gives the same ctx.extra (tested above)."""
    out = tmp_path / "pp"
    argv = ["run", "lee2009-projected-planes", "--quick", "--runs", "1", "--workers", "1"]
    assert main([*argv, "--no-progress", "--out", str(out), "--measurements", "audio"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert any(c["id"].startswith("audio_angles_") for c in summary["claims"])
    assert "--measurements audio" in (out / "report.md").read_text()
