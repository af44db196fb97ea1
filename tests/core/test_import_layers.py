"""Lower stages never import higher ones (docs/ARCHITECTURE.md): ``core`` <- ``motion``,
``sensors``, ``world`` <- ``filters`` <- ``association``, ``perception``, ``management``,
``tracking``, ``estimation`` <- ``evaluation`` <- ``experiments``, ``service``, ``tools``, ``cli``.
Checked on the source text of every module (imports inside functions count too), so it needs no
import of the package."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src" / "fusetrack"
RANK = {
    "core": 0,
    "motion": 1,
    "sensors": 1,
    "world": 1,
    "filters": 2,
    "association": 3,
    "perception": 3,
    "management": 3,
    "tracking": 3,
    "estimation": 3,
    "evaluation": 4,
    "experiments": 5,
    "service": 5,
    "tools": 5,
    "cli": 6,
}


def _imported_packages(path: Path) -> set[str]:
    """The fusetrack stages a module imports (absolute or relative)."""
    package = path.relative_to(SRC).parts[:-1]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(package[: len(package) - node.level + 1])
                parts = base + (node.module.split(".") if node.module else [])
            elif node.module and node.module.startswith("fusetrack."):
                parts = node.module.split(".")[1:]
            else:
                continue
            if parts:
                out.add(parts[0])
            elif node.level and not base:  # from .. import x at the top: x are stages
                out.update(a.name for a in node.names)
        elif isinstance(node, ast.Import):
            out.update(a.name.split(".")[1] for a in node.names if a.name.startswith("fusetrack."))
    return out


MODULES = sorted(
    p for p in SRC.rglob("*.py") if p.relative_to(SRC).parts[0] in RANK or p.stem in RANK
)


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(SRC)))
def test_no_module_imports_a_higher_stage(path):
    stage = path.relative_to(SRC).parts[0].removesuffix(".py")
    bad = sorted(p for p in _imported_packages(path) if RANK.get(p, -1) > RANK[stage])
    assert not bad, f"{path.relative_to(SRC)} ({stage}) imports the higher stage(s) {bad}"


def test_the_walk_sees_the_stages():
    assert {p.relative_to(SRC).parts[0] for p in MODULES} >= {"core", "filters", "service"}
