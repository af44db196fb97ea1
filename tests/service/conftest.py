"""Shared fixtures of the fusion node tests: the demo network with known keys."""

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
    """The demo network on the data clock, flushing 0.3 s after a stream pauses."""
    return demo_network(KEYS, idle_flush=0.3)
