"""Matplotlib is imported by one module only, ``evaluation/drawing.py`` (issue 20): every other
module draws through its helpers (``evaluation.plots`` re-exports them), so the style of all
figures (distinct curves, legends, units, shaded intervals) is set in one place."""

from __future__ import annotations

import ast
from pathlib import Path

import fusetrack

SRC = Path(fusetrack.__file__).parent
ALLOWED = {"evaluation/drawing.py"}


def matplotlib_uses(source: str) -> list[int]:
    """Lines that import matplotlib (any submodule) or use a name ``plt``."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            names = [node.module or ""]
        elif isinstance(node, ast.Name) and node.id == "plt":
            names = ["plt"]
        else:
            continue
        if any(n == "plt" or n.split(".")[0] == "matplotlib" for n in names):
            lines.append(node.lineno)
    return lines


def test_the_scan_finds_every_form_of_import():
    src = "import matplotlib\nfrom matplotlib.patches import Circle\nimport matplotlib.pyplot as p\nplt.close()\nimport numpy\n"
    assert matplotlib_uses(src) == [1, 2, 3, 4]


def test_only_drawing_imports_matplotlib():
    found = {
        f"{p.relative_to(SRC).as_posix()}:{line}"
        for p in sorted(SRC.rglob("*.py"))
        if p.relative_to(SRC).as_posix() not in ALLOWED
        for line in matplotlib_uses(p.read_text(encoding="utf-8"))
    }
    assert not found, f"draw through fusetrack.evaluation.drawing instead: {sorted(found)}"
