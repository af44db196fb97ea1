"""Each package's ``__init__`` is its public API (issue 16, item 6).

Code in one package imports another package's names through that package
(``from ..filters import ProposalParticleFilter``), never from a module inside it
(``from ..filters.sis import ...``), so modules can move inside a package without
touching callers.  Checked on every module of ``src/fusetrack``.  A package is a top-level
stage (``core``, ``filters``, ``service``, ...) with its sub-packages (``perception.video``),
except that each experiment (``experiments/zhai2007``) is a package of its own.
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

import fusetrack

SRC = Path(fusetrack.__file__).parent
# every package of fusetrack (core, ..., tools; a new one joins by existing)
STAGES = tuple(sorted(p.parent.name for p in SRC.glob("*/__init__.py")))

# (importing file, imported module) pairs that must stay module imports, and why.
EXEMPT = {
    # sensors and world import each other; through the packages that is a circular import.
    ("sensors/occlusion_aware_camera.py", "world.geometry"),
    ("sensors/occlusion_aware_camera.py", "world.occlusion"),
    ("sensors/occlusion_aware_camera.py", "world.occlusion_kernels"),
    ("sensors/occlusion_aware_camera.py", "world.room"),
}
# Modules whose import has side effects the package must not have (matplotlib's Agg backend).
MODULE_IMPORTS_ALLOWED = {"evaluation.plots"}


def checked_files() -> list[Path]:
    return sorted(SRC.rglob("*.py"))


def package_of(parts: list[str]) -> list[str]:
    """The package of a module given as its dotted path under ``fusetrack``, split."""
    if parts[0] == "experiments" and len(parts) >= 2 and (SRC / "experiments" / parts[1]).is_dir():
        return parts[:2]
    return parts[:1]


def imports_past_init(rel: Path, source: str) -> list[str]:
    """``file:line`` for every import from another package that names a module inside it."""
    package = rel.parts[:-1]
    own = package_of([*package, rel.stem]) if package else []
    found = []
    for node in ast.walk(ast.parse(source)):
        if not (isinstance(node, ast.ImportFrom) and node.level and node.module):
            continue
        base = list(package[: len(package) - node.level + 1])
        parts = base + node.module.split(".")
        target = package_of(parts)
        if target == own or target == parts:
            continue
        module = ".".join(parts)
        if module in MODULE_IMPORTS_ALLOWED or (str(rel), module) in EXEMPT:
            continue
        found.append(f"{rel}:{node.lineno} imports from {module}")
    return found


def test_the_checked_files_exist() -> None:
    assert len(checked_files()) > 100


@pytest.mark.parametrize("path", checked_files(), ids=lambda p: str(p.relative_to(SRC)))
def test_cross_package_imports_go_through_the_package(path: Path) -> None:
    assert imports_past_init(path.relative_to(SRC), path.read_text(encoding="utf-8")) == []


def test_the_check_sees_an_import_past_init() -> None:
    source = (
        "from ...filters import run_filter\n"
        "from .scene import Scene\n"
        "def f():\n"
        "    from ...filters.sis import (\n"
        "        ProposalParticleFilter,\n"
        "    )\n"
    )
    rel = Path("experiments/lee2009/probe.py")
    assert imports_past_init(rel, source) == [
        "experiments/lee2009/probe.py:4 imports from filters.sis"
    ]
    assert imports_past_init(Path("cli.py"), "from .core.errors import invalid\n") == [
        "cli.py:1 imports from core.errors"
    ]


def test_each_experiment_is_a_package_and_perception_video_is_part_of_perception() -> None:
    source = (
        "from .scene import Scene\n"
        "from ..zhai2007 import run_steps\n"
        "from ..zhai2007.common import run_steps\n"
        "from ..registry import REGISTRY\n"
        "from ...tools.track_video import track_video\n"
    )
    assert imports_past_init(Path("experiments/nott2009/probe.py"), source) == [
        "experiments/nott2009/probe.py:3 imports from experiments.zhai2007.common",
        "experiments/nott2009/probe.py:4 imports from experiments.registry",
        "experiments/nott2009/probe.py:5 imports from tools.track_video",
    ]
    inside = "from ..video.horprasert import SHADOW\nfrom ..appearance import features_from_rgb\n"
    assert imports_past_init(Path("perception/source_localisation/probe.py"), inside) == []


@pytest.mark.parametrize("stage", STAGES)
def test_every_exported_name_imports(stage: str) -> None:
    package = importlib.import_module(f"fusetrack.{stage}")
    names = getattr(package, "__all__", None) or [n for n in vars(package) if not n.startswith("_")]
    missing = [name for name in names if not hasattr(package, name)]
    assert missing == []
    namespace: dict[str, object] = {}
    exec(f"from fusetrack.{stage} import *", namespace)
    assert set(getattr(package, "__all__", [])) <= set(namespace)
