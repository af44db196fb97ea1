"""Lee 2009 Sec. 5.2.3: the traffic model's orderings (C18) and bad input."""

import json

import pytest

from fusetrack.cli import main
from fusetrack.core.errors import ConfigError
from fusetrack.management.network_traffic import NetworkConfig, simulate_traffic


def _d(protocol, objs, cams, **kw):
    return simulate_traffic(
        NetworkConfig(
            protocol=protocol, routers_with_objects=objs, camera_routers=cams, rounds=2, **kw
        )
    )["end_to_end"]


def test_orderings():
    assert _d("RBVC", (1,), (2, 4)) < _d("SBVC", (1,), (2, 4))
    everywhere = (1, 2, 3, 4, 5)
    assert _d("SBVC", everywhere, (2, 4)) < _d("RBVC", everywhere, (2, 4))
    assert _d("SBVC", everywhere, (5,)) < _d("SBVC", everywhere, (2, 4))
    small, big = (
        _d("RBVC", (1,), (2, 4), image_bytes=10_000),
        _d("RBVC", (1,), (2, 4), image_bytes=100_000),
    )
    assert big > 5 * small


def test_bad_config():
    with pytest.raises(ConfigError, match="protocol"):
        NetworkConfig(protocol="P2P")
    with pytest.raises(ConfigError, match="camera_routers"):
        NetworkConfig(camera_routers=(9,))


def test_traffic_experiment_quick(tmp_path):
    assert main(["run", "lee2009-network-traffic", "--quick", "--out", str(tmp_path)]) == 0
    s = json.loads((tmp_path / "summary.json").read_text())
    assert len(s["claims"]) == 4
