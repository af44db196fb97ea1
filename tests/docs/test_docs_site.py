"""The documentation site's generated parts (``docs/_hooks/fusetrack_docs.py``) cover the code:
every public package has an API page in the nav, every experiment is on a paper page, the CLI
reference has every subcommand. ``mkdocs build --strict`` itself runs in ``.ci/run``."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

pytest.importorskip("mkdocs", reason="the docs extra: pip install -e '.[docs]'")

ROOT = Path(__file__).resolve().parents[2]
NOT_IN_API = {"experiments", "tools"}  # run through the CLI; their parts are in the packages


def _hooks():
    spec = importlib.util.spec_from_file_location(
        "fusetrack_docs", ROOT / "docs/_hooks/fusetrack_docs.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_public_package_has_an_api_page_in_the_nav():
    packages = {p.parent.name for p in (ROOT / "src/fusetrack").glob("*/__init__.py")}
    pages = {p.stem for p in (ROOT / "docs/api").glob("*.md")}
    assert pages == packages - NOT_IN_API
    nav = (ROOT / "mkdocs.yml").read_text()
    for name in pages:
        assert f"api/{name}.md" in nav
        assert (ROOT / f"docs/api/{name}.md").read_text().strip().endswith(f"::: fusetrack.{name}")


def test_api_members_are_the_package_exports():
    hooks = _hooks()
    names, modules = hooks.public_names("fusetrack.filters")
    assert {"KalmanFilter", "run_filter", "BootstrapFilter"} <= set(names)
    assert not any(n.startswith("_") for n in names) and modules == []
    names, modules = hooks.public_names("fusetrack.perception")
    assert "source_localisation" in modules and "source_localisation" not in names
    block = hooks.api_block("fusetrack.perception")
    assert "::: fusetrack.perception.source_localisation" in block and '"Beamformer"' in block


def test_every_experiment_is_on_a_paper_page():
    from fusetrack.experiments import REGISTRY

    pages = " ".join(p.read_text() for p in (ROOT / "docs/papers").glob("*.md"))
    prefixes = re.findall(r"\{\{ experiments ([\w-]+) \}\}", pages)
    missing = [n for n in REGISTRY if n != "demo" and not n.startswith(tuple(prefixes))]
    assert missing == []
    table = _hooks().experiments_table("ercan2013", "papers/ercan2013.md")
    assert "[`ercan2013-cameras`](../reports/ercan2013-cameras/report.md)" in table
    cells = [len(re.findall(r"(?<!\\)\|", row)) for row in table.splitlines()]
    assert cells == [5] * len(cells)  # four columns in every row: no bare bar inside a cell


def test_cli_reference_has_every_subcommand_with_its_options():
    from fusetrack.cli import build_parser

    text = _hooks().cli_reference()
    parser = build_parser()
    commands = parser._subparsers._group_actions[0].choices
    for name in commands:
        assert f"## fusetrack {name}\n" in text
        assert f"usage: fusetrack {name} " in text
    assert "--set sigma_psi=FLOAT (default 31.0)" in text  # run NAME --help's options


def test_a_missing_report_figure_is_a_note_not_a_broken_link():
    hooks = _hooks()
    shown = hooks.figure("ercan2013-cameras/fig6_rmse_vs_cameras.png", "Fig. 6", "papers/x.md")
    assert shown.startswith("![Fig. 6](../reports/ercan2013-cameras/fig6_rmse_vs_cameras.png)")
    note = hooks.figure("nott2009-none/fig.png", "A figure", "papers/x.md")
    assert note.startswith("!!! note") and "](" not in note
    assert "fusetrack run nott2009-none --out reports/nott2009-none" in note


def test_readme_commands_are_taken_from_the_readme():
    code = _hooks().readme_code("# fusetrack")
    assert code.startswith("```bash") and code.endswith("```")
    assert 'pip install -e ".[dev,docs]" && .venv/bin/python -m pytest -q -n auto' in code
    with pytest.raises(ValueError, match="no line"):
        _hooks().readme_code("## No such heading")


def test_paper_pages_get_their_verdict():
    text = _hooks().verdicts("nott2009", "papers/nott2009.md")
    assert text.startswith("**Verdict on Nott 2009's central contributions**")
    assert "[nott2009-simulation](../reports/nott2009-simulation/report.md) `H1-S1`" in text
