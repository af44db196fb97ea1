"""Run a script of ``benchmarks/`` with ``--json`` and read what it prints (for the smoke tests)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

BENCH = Path(__file__).resolve().parents[2] / "benchmarks"


def bench_json(script: str, *args: str, timeout: float = 600) -> list[Any]:
    """Every JSON document ``benchmarks/<script> <args> --json`` prints, in order.

    One indented document or one document a line both work. A nonzero exit fails the test
    with the script's stderr.
    """
    out = subprocess.run(
        [sys.executable, str(BENCH / script), *args, "--json"],
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    decoder, text, docs, i = json.JSONDecoder(), out.stdout, [], 0
    while True:
        while i < len(text) and text[i].isspace():
            i += 1
        if i == len(text):
            return docs
        doc, i = decoder.raw_decode(text, i)
        docs.append(doc)
