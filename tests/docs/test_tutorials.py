"""The tutorials (``docs/tutorials/NN_name.py``) run at their quick size, write their figure and
get the results their text describes; each has a committed full-size figure and a page in the
site's nav, and its page shows its code."""

from __future__ import annotations

import importlib.util
import runpy
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
TUTORIALS = ROOT / "docs" / "tutorials"
NAMES = sorted(p.stem for p in TUTORIALS.glob("[0-9][0-9]_*.py"))
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run_quick(name: str, out: Path, monkeypatch: pytest.MonkeyPatch) -> dict:
    """Run the tutorial as a script (``__main__``) with ``--quick --out OUT``; its globals."""
    monkeypatch.setattr(sys, "argv", [f"{name}.py", "--quick", "--out", str(out)])
    monkeypatch.delenv("FUSETRACK_QUICK", raising=False)
    return runpy.run_path(str(TUTORIALS / f"{name}.py"), run_name="__main__")


def test_there_are_at_least_six_tutorials():
    assert len(NAMES) >= 6, NAMES


@pytest.mark.parametrize("name", NAMES)
def test_a_tutorial_runs_quick_and_writes_its_figure(name, tmp_path, monkeypatch):
    result = run_quick(name, tmp_path, monkeypatch)
    assert result["args"].quick
    figure = tmp_path / f"{name}.png"
    assert figure.read_bytes()[:8] == PNG_MAGIC
    assert [p.name for p in tmp_path.iterdir()] == [figure.name]  # nothing else left behind
    CHECKS.get(name, lambda r: None)(result)


def test_the_quick_switch_is_also_an_environment_variable(tmp_path, monkeypatch):
    name = "06_live_node_from_recordings"
    monkeypatch.setattr(sys, "argv", [f"{name}.py", "--out", str(tmp_path)])
    monkeypatch.setenv("FUSETRACK_QUICK", "1")
    result = runpy.run_path(str(TUTORIALS / f"{name}.py"), run_name="__main__")
    assert result["args"].quick and result["duration"] == 30.0
    assert (tmp_path / f"{name}.png").exists()


def _first_filter(r: dict) -> None:
    assert r["err_kf"].mean() < r["err_tag"].mean()  # the filter beats the raw fixes
    assert r["err_ekf"].mean() < 1.5  # the radar EKF converged (metres)


def _fusing(r: dict) -> None:
    errors = {k: v.mean() for k, v in r["errors"].items()}
    assert errors["EKF"] < errors["EKF without the camera"] < errors["EKF, tag alone"]


def _own_model(r: dict) -> None:
    rmse = {k: v.mean() for k, v in r["rmse"].items()}
    assert rmse["PF-SP-PEKF, N=30, 20 EKFs"] < rmse["bootstrap, N=30"] < rmse["EKF"]


def _several_targets(r: dict) -> None:
    for name, g in r["gospa"].items():
        assert g.distance.mean() < 5.0, name  # metres, cut-off 10: the targets are tracked


def _fit(r: dict) -> None:
    assert r["fit"].success
    q_lo, q_hi = r["q_hat"] * np.exp(1.96 * np.array([-1, 1]) * r["se"][0])
    s_lo, s_hi = r["sigma_hat"] * np.exp(1.96 * np.array([-1, 1]) * r["se"][1])
    assert q_lo < r["true_q"] < q_hi and s_lo < r["true_sigma"] < s_hi


def _live_node(r: dict) -> None:
    assert r["refused"] == {} and r["outcome"].reason == "replay"
    assert r["published"][-1].time == pytest.approx(r["duration"])  # the last ticks flushed
    assert not Path(r["workdir"]).exists()  # the scratch directory is removed


def _ercan(r: dict) -> None:
    assert r["hidden"] > 0.1  # the occlusion-aware part of the likelihood has work to do
    for mode, error in r["errors"].items():  # a lost tracker is ~30 units off in this room
        assert np.all(np.isfinite(error)) and error[-20:].mean() < 2 * r["diameter"], mode


CHECKS = {
    "01_first_filter": _first_filter,
    "02_fusing_sensors": _fusing,
    "03_zhai_proposal_own_model": _own_model,
    "04_several_targets": _several_targets,
    "05_fit_noise_by_likelihood": _fit,
    "06_live_node_from_recordings": _live_node,
    "07_ercan_occlusion_own_room": _ercan,
}


def test_every_tutorial_has_its_checks_a_committed_figure_and_a_page_in_the_nav():
    assert sorted(CHECKS) == NAMES
    nav = (ROOT / "mkdocs.yml").read_text()
    for name in NAMES:
        assert (TUTORIALS / "figures" / f"{name}.png").read_bytes()[:8] == PNG_MAGIC, name
        assert (TUTORIALS / f"{name}.md").read_text().strip() == f"{{{{ tutorial {name} }}}}"
        assert f"tutorials/{name}.md" in nav


def test_a_tutorial_page_shows_the_docstring_the_figure_and_the_code():
    pytest.importorskip("mkdocs", reason="the docs extra: pip install -e '.[docs]'")
    spec = importlib.util.spec_from_file_location(
        "fusetrack_docs", ROOT / "docs/_hooks/fusetrack_docs.py"
    )
    hooks = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hooks)
    page = hooks.tutorial("01_first_filter")
    assert page.startswith("# A first filter: one target, one sensor, a Kalman filter\n")
    assert "![The figure 01_first_filter.py writes](figures/01_first_filter.png)" in page
    code = page.split("```python\n", 1)[1]
    assert code.startswith("import argparse\n") and code.endswith("\n```")
    assert '"""' not in code.split("def options", 1)[0]  # the docstring is the text, not code
