"""Golden test: every experiment's ``--quick`` claims at seed 11 equal the recorded fixture.

CI runs the experiments that took at most ``CI_SECONDS`` when recorded; ``FUSETRACK_GOLDEN=all``
runs every one (do that before landing a change that moves code an experiment uses).
"""

from __future__ import annotations

import os

import pytest

from .golden import FLOATING_POINT, TIMING, claim_differences, load
from .record import run_quick

GOLDEN = load()
CI_SECONDS = 12.0
ALL = os.environ.get("FUSETRACK_GOLDEN") == "all"
NAMES = sorted(n for n, g in GOLDEN.items() if ALL or g["seconds"] <= CI_SECONDS)


def test_fixture_covers_every_experiment():
    from fusetrack.experiments import REGISTRY

    assert sorted(GOLDEN) == sorted(REGISTRY)


def test_presence_only_claims_are_recorded_claims():
    """Every timing / floating-point exemption names a claim of the fixture (no typo exempts
    nothing, and nothing is exempted by a name that does not exist)."""
    for table in (TIMING, FLOATING_POINT):
        for name, ids in table.items():
            assert ids <= GOLDEN[name]["claims"].keys(), (name, ids - GOLDEN[name]["claims"].keys())


@pytest.mark.parametrize("name", NAMES)
def test_quick_claims_unchanged(name):
    got = run_quick(name)["claims"]
    assert claim_differences(name, GOLDEN[name]["claims"], got) == []
