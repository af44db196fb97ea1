"""Compare an experiment's ``--quick`` claims with the golden fixture (``quick_claims.json``).

The fixture was recorded before the "one tracking model" reshaping (issue 16) by ``record.py``;
a reshaping must leave every claim's ``ours`` value where it was: numbers to 1e-9 (relative),
text exactly.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

FIXTURE = Path(__file__).with_name("quick_claims.json")
RTOL = 1e-9


def load() -> dict[str, dict[str, Any]]:
    return json.loads(FIXTURE.read_text())


def differences(expected: Any, got: Any, where: str = "") -> list[str]:
    """Every place where ``got`` differs from ``expected`` (empty when they agree)."""
    if isinstance(expected, bool) or isinstance(got, bool):
        return [] if expected == got else [f"{where}: {got!r} != golden {expected!r}"]
    if isinstance(expected, int | float) and isinstance(got, int | float):
        if math.isnan(expected) and math.isnan(got):
            return []
        if math.isclose(expected, got, rel_tol=RTOL, abs_tol=1e-12):
            return []
        return [f"{where}: {got!r} != golden {expected!r}"]
    if isinstance(expected, dict) and isinstance(got, dict):
        out = (
            [f"{where}: keys {sorted(set(got) ^ set(expected))} differ"]
            if set(got) != set(expected)
            else []
        )
        for k in expected.keys() & got.keys():
            out += differences(expected[k], got[k], f"{where}.{k}")
        return out
    if isinstance(expected, list) and isinstance(got, list) and len(expected) == len(got):
        out: list[str] = []
        for i, (e, g) in enumerate(zip(expected, got, strict=True)):
            out += differences(e, g, f"{where}[{i}]")
        return out
    return [] if expected == got else [f"{where}: {got!r} != golden {expected!r}"]
