"""``fusetrack reports tally``: every claim has a kind, and reports/README.md's tally is the one
generated from the committed summaries."""

import json
from pathlib import Path

import pytest

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.experiments import REGISTRY, claim_kinds
from fusetrack.tools.report_tally import (
    readme_tally,
    tally_experiment,
    tally_markdown,
    write_tally,
)

ROOT = Path(__file__).resolve().parents[2]
REPORTS = ROOT / "reports"
GOLDEN = json.loads((ROOT / "tests" / "golden" / "quick_claims.json").read_text())


def test_readme_tally_is_the_generated_one():
    assert readme_tally(REPORTS / "README.md") == tally_markdown(REPORTS)


@pytest.mark.parametrize("name", sorted(n for n in REGISTRY if not n.startswith("multitarget-")))
def test_every_claim_of_every_experiment_has_a_kind(name):
    """The golden fixture holds every experiment's claim ids: each has a kind in its table (the
    multitarget experiments set each claim's kind where they make it)."""
    kinds = claim_kinds(name)
    assert kinds is not None, f"{name} has no CLAIM_KINDS"
    for claim_id in GOLDEN[name]["claims"]:
        kinds.kind_of(claim_id)


def _summary(folder: Path, name: str, claims: list[dict], **extra) -> Path:
    folder.mkdir(parents=True)
    (folder / "summary.json").write_text(
        json.dumps({"experiment": name, "claims": claims, **extra})
    )
    return folder


def test_kinds_from_the_summary_the_recorded_map_or_the_table(tmp_path):
    new = _summary(
        tmp_path / "lee2009-face-matching",
        "lee2009-face-matching",
        [
            {"id": "x", "holds": True, "kind": "beyond"},
            {"id": "C16_within_race_fails", "holds": False},  # old: the table says paper
            {"id": "C16_rho_bounds", "holds": True},  # retired: held by construction
        ],
    )
    t = tally_experiment(new)
    assert (t.held, t.total) == (
        {"paper": 0, "calibration": 0, "diagnostic": 0, "beyond": 1},
        {"paper": 1, "calibration": 0, "diagnostic": 0, "beyond": 1},
    )
    assert t.retired == ["lee2009-face-matching C16_rho_bounds"]
    recorded = _summary(
        tmp_path / "multitarget-bearings",
        "multitarget-bearings",
        [{"id": "g", "holds": True}],
        beyond_the_paper={"claim_kinds": {"g": "diagnostic"}},
    )
    assert tally_experiment(recorded).held["diagnostic"] == 1
    block = tally_markdown(tmp_path)
    assert "**0 of 1 paper claims hold**" in block and "| Lee 2009 | 0 of 1 |" in block
    assert "Not counted: 1 claim(s)" in block


def test_an_unknown_claim_id_is_an_error(tmp_path):
    _summary(tmp_path / "zhai2007-mcmc", "zhai2007-mcmc", [{"id": "nope", "holds": True}])
    with pytest.raises(ConfigError, match="claim id='nope'"):
        tally_markdown(tmp_path)


def test_write_replaces_only_the_block(tmp_path, capsys):
    """(A folder without any paper's report.md: no verdict block is written.)"""
    _summary(tmp_path / "zhai2007-mcmc", "zhai2007-mcmc", [{"id": "C15_order_N100", "holds": True}])
    readme = tmp_path / "README.md"
    readme.write_text("# Reports\n\nIntro.\n")
    assert main(["reports", "tally", "--reports", str(tmp_path), "--write"]) == 0
    first = readme.read_text()
    assert first.startswith("# Reports\n\nIntro.\n") and "| zhai2007-mcmc | 1 of 1 |" in first
    assert not write_tally(readme, tally_markdown(tmp_path))  # a second write changes nothing
    readme.write_text(first + "\nAfter.\n")
    write_tally(readme, tally_markdown(tmp_path))
    assert readme.read_text() == first + "\nAfter.\n"
    assert main(["reports", "tally", "--reports", str(tmp_path)]) == 0
    assert "| zhai2007-mcmc | 1 of 1 |" in capsys.readouterr().out


def test_wall_times_against_the_30_minute_budget(tmp_path):
    """Each experiment's row shows the wall time of the run that wrote its summary; runs over 30
    minutes are bold and named in the line below the table; a summary without seconds shows -."""
    claim = [{"id": "C15_order_N100", "holds": True}]
    _summary(tmp_path / "zhai2007-mcmc", "zhai2007-mcmc", claim, seconds=561.2, workers=2)
    _summary(tmp_path / "zhai2007-scalar", "zhai2007-scalar", [], seconds=1800.5, workers=1)
    _summary(tmp_path / "zhai2007-galerkin", "zhai2007-galerkin", [])
    machine = {"cpu_model": "AMD EPYC", "cpu_arch": "znver4", "avx512": True, "cores": 2}
    _summary(
        tmp_path / "zhai2007-grid", "zhai2007-grid", [], seconds=60, workers=2, machine=machine
    )
    block = tally_markdown(tmp_path)
    assert "| zhai2007-grid | – | – | – | – | 1.0 min (2 workers, znver4) |" in block
    assert "| zhai2007-mcmc | 1 of 1 | – | – | – | 9.4 min (2 workers) |" in block
    assert "| zhai2007-scalar | – | – | – | – | **30.0 min (1 worker)** |" in block
    assert "| zhai2007-galerkin | – | – | – | – | – |" in block
    assert (
        "2 of 3 within 30 minutes; over it (bold): zhai2007-scalar 30 min." in block
        and "| Zhai 2007 | 1 of 1 | – | – | – |\n" in block  # per paper: no time column
    )
