"""The reliability suite's network: the demo network with known keys, on the data clock."""

from __future__ import annotations

import pytest

from fusetrack.service.replay import demo_network

KEYS = {
    "array-west": "test-key-array-west-000001",
    "array-east": "test-key-array-east-000002",
    "camera-1": "test-key-camera-1-00000003",
    "tag-reader": "test-key-tag-reader-000004",
}


@pytest.fixture
def network():
    return demo_network(KEYS)
