"""``fusetrack reports verdicts``: every paper's verdict, computed from the committed summaries,
is the one in reports/README.md and at the top of each of the paper's reports; a verdict naming a
claim the reports do not have fails here."""

import json
import shutil
from pathlib import Path

import pytest

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.experiments import PAPERS, paper_verdicts
from fusetrack.tools.report_tally import refresh_reports_folder
from fusetrack.tools.report_verdicts import (
    BEGIN,
    committed_block,
    readme_block,
    report_block,
    report_paths,
    summary_claims,
    write_verdicts,
)

ROOT = Path(__file__).resolve().parents[2]
REPORTS = ROOT / "reports"
FIX = "run `fusetrack reports tally --write` after copying full-size runs into reports/"


def test_every_paper_declares_its_verdict():
    assert [v.prefix for v in paper_verdicts()] == list(PAPERS)
    for verdict in paper_verdicts():
        assert verdict.contributions and report_paths(REPORTS, verdict)


def test_readme_verdicts_are_the_generated_ones():
    assert committed_block(REPORTS / "README.md") == readme_block(REPORTS), FIX


def test_every_report_opens_with_its_papers_verdict():
    claims = summary_claims(REPORTS)
    for verdict in paper_verdicts():
        for path in report_paths(REPORTS, verdict):
            expected = report_block(verdict, claims, path.parent.name)
            assert committed_block(path) == expected, f"{path.relative_to(ROOT)}: {FIX}"
            title, blank, first = path.read_text().splitlines()[:3]
            assert title.startswith("# ") and blank == "" and first == BEGIN


def _copy(tmp_path: Path, names: list[str]) -> Path:
    reports = tmp_path / "reports"
    for name in names:
        (reports / name).mkdir(parents=True)
        shutil.copy(REPORTS / name / "summary.json", reports / name / "summary.json")
    return reports


def test_write_inserts_then_replaces_the_blocks(tmp_path):
    reports = _copy(
        tmp_path, [p.name for p in REPORTS.glob("*2*-*") if (p / "summary.json").exists()]
    )
    report = reports / "nott2009-radio-accuracy" / "report.md"
    report.write_text("# Title\n\n`fusetrack run ...`\n\n## Claims\n")
    (reports / "README.md").write_text("# Reports\n\n## Tally\n\nold\n")
    assert main(["reports", "verdicts", "--reports", str(reports), "--write"]) == 0
    text = report.read_text()
    assert text.startswith(f"# Title\n\n{BEGIN}\n\n**Verdict on Nott 2009's")
    assert text.endswith("<!-- end of verdicts -->\n\n`fusetrack run ...`\n\n## Claims\n")
    readme = (reports / "README.md").read_text()
    assert readme.index("## Verdicts") < readme.index("### Nott 2009") < readme.index("## Tally")
    assert write_verdicts(reports) == []  # a second write changes nothing


def test_a_claim_missing_from_the_summary_is_an_error(tmp_path):
    reports = _copy(
        tmp_path, [p.name for p in REPORTS.glob("*2*-*") if (p / "summary.json").exists()]
    )
    path = reports / "nott2009-simulation" / "summary.json"
    summary = json.loads(path.read_text())
    summary["claims"] = [c for c in summary["claims"] if c["id"] != "H1-S2"]
    path.write_text(json.dumps(summary))
    (path.parent / "report.md").write_text("# Nott\n")
    with pytest.raises(ConfigError, match="claim id of nott2009-simulation='H1-S2'"):
        readme_block(reports)


def test_paper_pages_show_the_verdict():
    for prefix in PAPERS:
        page = (ROOT / "docs" / "papers" / f"{prefix}.md").read_text()
        assert page.splitlines()[2] == f"{{{{ verdicts {prefix} }}}}"


def test_a_full_size_run_into_a_reports_folder_refreshes_it(tmp_path):
    """`fusetrack run NAME --out reports/NAME` (and `reproduce`) rewrite the generated blocks of
    a reports folder; elsewhere nothing happens; a stale verdict is said, not raised."""
    assert refresh_reports_folder(tmp_path / "nott2009-video") is None
    reports = _copy(
        tmp_path, [p.name for p in REPORTS.glob("*2*-*") if (p / "summary.json").exists()]
    )
    (reports / "nott2009-video" / "report.md").write_text("# Video\n")
    (reports / "README.md").write_text("# Reports\n")
    assert refresh_reports_folder(reports / "nott2009-video") is None  # no tally markers
    (reports / "README.md").write_text((REPORTS / "README.md").read_text())
    note = refresh_reports_folder(reports / "nott2009-video")
    assert note is not None and "updated in 2 file(s)" in note
    assert (reports / "nott2009-video" / "report.md").read_text().startswith(f"# Video\n\n{BEGIN}")
    path = reports / "nott2009-video" / "summary.json"
    summary = json.loads(path.read_text())
    summary["claims"] = [c for c in summary["claims"] if c["id"] != "H6"]
    path.write_text(json.dumps(summary))
    note = refresh_reports_folder(reports / "nott2009-video")
    assert "NOT updated" in note and "'H6'" in note
