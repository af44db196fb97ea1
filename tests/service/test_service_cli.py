"""``fusetrack demo --live``, ``fusetrack replay`` (into a running node) and ``serve``'s errors;
the wall clock."""

from __future__ import annotations

import re

import httpx
import numpy as np

from fusetrack.cli import main
from fusetrack.service.config import load_config
from fusetrack.service.node import FusionNode
from fusetrack.service.schema import SensorMessage, reading_from_vector
from fusetrack.service.server import RunningNode, build_node


def test_demo_live_prints_the_address_and_tracks(capsys):
    code = main(
        [
            "demo",
            "--live",
            "--speed",
            "inf",
            "--duration",
            "10",
            "--port",
            "0",
            "--exit-after-replay",
        ]
    )
    out = capsys.readouterr().out
    assert code == 0
    assert re.search(r"dashboard: http://127\.0\.0\.1:\d+/", out)
    ticks = int(re.search(r"(\d+) ticks", out).group(1))
    err = float(re.search(r"final position error ([\d.]+) m", out).group(1))
    assert ticks == 20 and err < 8.0  # 4.2 m for this seed after 10 s; lost tracks are 20+ m


def test_replay_command_into_a_node_of_the_example_config(capsys):
    cfg = load_config("examples/network.yaml")
    cfg = cfg.model_copy(update={"fusion": cfg.fusion.model_copy(update={"idle_flush": 0.2})})
    with RunningNode(build_node(cfg)) as node:
        code = main(
            [
                "replay",
                "demo",
                "--to",
                node.url,
                "--config",
                "examples/network.yaml",
                "--speed",
                "inf",
                "--duration",
                "5",
                "--encoding",
                "msgpack",
            ]
        )
        assert code == 0
        assert "sent" in capsys.readouterr().out
        h = httpx.get(node.url + "/health").json()
    assert h["accepted"] > 20 and sum(h["rejected"].values()) == 0


def test_cli_errors_name_the_problem(tmp_path, capsys):
    bad = tmp_path / "net.yaml"
    bad.write_text("sensors: []\n")
    assert main(["serve", "--config", str(bad), "--port", "0"]) == 2
    assert "sensors" in capsys.readouterr().err
    assert main(["replay", "demo", "--to", "ftp://x:1", "--config", "examples/network.yaml"]) == 2
    assert "--to" in capsys.readouterr().err


def test_wall_clock_ticks_follow_the_node_clock(network):
    cfg = network.model_copy(
        update={
            "fusion": network.fusion.model_copy(
                update={"clock": "wall", "lag": 0.25, "rate_hz": 4.0}
            )
        }
    )
    clock = [1_800_000_000.1]
    node = FusionNode(cfg, wall=lambda: clock[0])
    start = node.aligner.start
    assert start == 1_800_000_000.0  # on the 4 Hz grid
    m = SensorMessage(
        node="tag-reader",
        seq=1,
        sensor="tag",
        time=clock[0],
        reading=reading_from_vector("position_fix", [21.0, 19.0]),
    )
    assert node.ingest_message(m, "tag-reader").accepted
    far = m.model_copy(update={"seq": 2, "time": clock[0] + 60.0})
    assert node.ingest_message(far, "tag-reader").reason == "future"
    clock[0] = start + 0.25 + 0.25 - 1e-6
    assert node.advance() == []  # tick 1 (at +0.25) waits for the lag
    clock[0] = start + 1.0
    states = node.advance()
    assert [s.tick for s in states] == [1, 2, 3]  # due by +1.0: ends 0.25, 0.5, 0.75 plus lag
    assert states[0].readings == 1 and states[1].readings == 0
    assert np.isclose(states[0].time, start + 0.25)
    assert "fusetrack_tick_delay_seconds_count 3.0" in node.metrics_text().decode()


def test_replay_refuses_bad_sources_and_a_dead_node_before_sending(tmp_path, capsys):
    """Issue 18: a missing .sqlite was created empty ("sent 0 messages", exit 0); a bad .jsonl
    line and a node that is not running ended in tracebacks."""
    config = "examples/network.yaml"
    missing = tmp_path / "missing.sqlite"
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"node": "west", "seq": 1}\n{bad json\n')
    to = "http://127.0.0.1:9"  # the discard port: nothing listens
    assert main(["replay", str(missing), "--to", to, "--config", config]) == 2
    assert not missing.exists()
    assert main(["replay", str(bad), "--to", to, "--config", config]) == 2
    assert main(["replay", "demo", "--to", to, "--config", config, "--duration", "1"]) == 2
    err = capsys.readouterr().err
    assert (
        "an existing file" in err and "bad.jsonl line 1" in err and "running fusetrack node" in err
    )
    assert "Traceback" not in err


def test_websocket_frames_over_the_message_limit_are_refused_unbuffered(network):
    """Issue 18: WebSocket ingest buffered frames up to uvicorn's 16 MiB before the node's
    64 KiB message limit applied; the server now closes on a larger frame (1009, too big)."""
    import pytest
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    from fusetrack.service.auth import bearer_token

    key = next(iter(network.keys().values()))
    with RunningNode(build_node(network)) as node:
        url = node.url.replace("http://", "ws://") + "/ws/ingest"
        headers = {"Authorization": f"Bearer {bearer_token(key)}"}
        with connect(url, additional_headers=headers) as ws:
            with pytest.raises(ConnectionClosed) as closed:
                ws.send("x" * (network.limits.max_message_bytes + 1))
                ws.recv(timeout=10)
    assert closed.value.rcvd is not None and closed.value.rcvd.code == 1009
