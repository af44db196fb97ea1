"""Record (or check) every experiment's ``--quick`` claims at a fixed seed: the golden fixture.

    python tests/golden/record.py            # write tests/golden/quick_claims.json
    python tests/golden/record.py NAME ...   # only these experiments (merged into the file)
    python tests/golden/record.py --check [NAME ...]   # compare with the file, write nothing

Each experiment runs as ``fusetrack run NAME --quick --runs 1 --seed 11 --workers 1`` in a
temporary directory; the fixture keeps every claim's ``ours`` value and the wall time, so that the
golden test (``test_golden_quick.py``) can pick the experiments cheap enough for CI.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

FIXTURE = Path(__file__).with_name("quick_claims.json")
SEED = 11
ARGS = ["--quick", "--runs", "1", "--seed", str(SEED), "--workers", "1", "--no-progress"]


def run_quick(name: str) -> dict:
    """Run one experiment at the golden settings; return ``{"seconds", "claims": {id: ours}}``."""
    from fusetrack.cli import main

    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        code = main(["run", name, *ARGS, "--out", tmp])
        seconds = time.perf_counter() - start
        if code != 0:
            raise RuntimeError(f"{name}: exit code {code}")
        summary = json.loads((Path(tmp) / "summary.json").read_text())
    return {"seconds": round(seconds, 1), "claims": {c["id"]: c["ours"] for c in summary["claims"]}}


def check(names: list[str]) -> int:
    """Run ``names`` (default: all) and print where they differ from the fixture; 1 if any does."""
    sys.path.insert(0, str(Path(__file__).parent))
    from golden import claim_differences, floating_point_notes, load

    golden, bad = load(), 0
    for name in names or sorted(golden):
        got = run_quick(name)["claims"]
        diff = claim_differences(name, golden[name]["claims"], got)
        notes = [
            f"(floating point) {n}" for n in floating_point_notes(name, golden[name]["claims"], got)
        ]
        bad += bool(diff)
        print(f"{name}: {'OK' if not diff else 'DIFFERS'}", *diff, *notes, sep="\n  ", flush=True)
    return int(bad > 0)


def main(names: list[str]) -> None:
    from fusetrack.experiments import REGISTRY

    if names[:1] == ["--check"]:
        sys.exit(check(names[1:]))
    data = json.loads(FIXTURE.read_text()) if FIXTURE.exists() else {}
    for name in names or list(REGISTRY):
        data[name] = run_quick(name)
        FIXTURE.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
        print(f"{name}: {data[name]['seconds']} s, {len(data[name]['claims'])} claims", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
