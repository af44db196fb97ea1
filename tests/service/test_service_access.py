"""Issue 18, item 5: no TLS and no read protection on a node bound to 0.0.0.0. ``serve
--tls-cert/--tls-key`` serves HTTPS/WSS; ``readers`` in the config are read-only tokens: once
any is configured, tracks, sensors, health, metrics and /ws/tracks need a token."""

from __future__ import annotations

import shutil
import ssl
import subprocess

import httpx
import pytest
from fastapi.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.service.app import create_app
from fusetrack.service.auth import bearer_token
from fusetrack.service.config import parse_config
from fusetrack.service.node import FusionNode
from fusetrack.service.schema import SensorMessage, reading_from_vector
from fusetrack.service.server import RunningNode, tls_options

READER_KEY = "test-key-dashboard-reader-01"


def _message(seq=1):
    return SensorMessage(
        node="array-west",
        seq=seq,
        sensor="mic_west",
        time=1.0,
        reading=reading_from_vector("bearing", [0.2]),
    )


@pytest.fixture
def certificate(tmp_path):
    """A self-signed certificate for 127.0.0.1 made with the openssl command."""
    if shutil.which("openssl") is None:
        pytest.skip("no openssl command to make a test certificate")
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
         "-nodes", "-keyout", str(key), "-out", str(cert), "-days", "1",
         "-subj", "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1"],
        check=True,
        capture_output=True,
    )  # fmt: skip
    return cert, key


def test_tls_serves_https_and_refuses_plain_http(network, certificate):
    cert, key = certificate
    node = FusionNode(network)
    trust = ssl.create_default_context(cafile=str(cert))
    with RunningNode(node, udp_port=None, tls=tls_options(cert, key)) as running:
        assert running.url.startswith("https://")
        assert httpx.get(running.url + "/health", verify=trust).status_code == 200
        token = node.tokens["array-west"]
        r = httpx.post(
            running.url + "/ingest",
            content=_message().model_dump_json(),
            headers={"Authorization": f"Bearer {token}"},
            verify=trust,
        )
        assert r.status_code == 200 and r.json()["accepted"] == 1
        with pytest.raises(httpx.HTTPError):
            httpx.get(running.url.replace("https", "http") + "/health", timeout=2.0)
        with pytest.raises(httpx.ConnectError):  # a client that does not trust the certificate
            httpx.get(running.url + "/health")


def test_bad_tls_options_are_refused_before_work(tmp_path, certificate, capsys):
    cert, key = certificate
    with pytest.raises(ConfigError, match="together"):
        tls_options(cert, None)
    junk = tmp_path / "junk.pem"
    junk.write_text("not a certificate")
    with pytest.raises(ConfigError, match="PEM certificate"):
        tls_options(junk, key)
    with pytest.raises(ConfigError, match="PEM certificate"):
        tls_options(cert, tmp_path / "missing.pem")
    log = tmp_path / "node.sqlite"
    argv = ["serve", "--config", "examples/network.yaml", "--log", str(log), "--port", "0"]
    assert main([*argv, "--tls-cert", str(cert)]) == 2
    assert "--tls-key together" in capsys.readouterr().err
    assert not log.exists()  # refused before the log was opened


def _with_reader(network):
    data = network.model_dump(mode="json")
    data["readers"] = [{"id": "dashboard", "key": READER_KEY}]
    return parse_config(data)


def test_reader_tokens_read_but_never_post(network):
    cfg = _with_reader(network)
    assert cfg.fingerprint() == network.fingerprint()  # access is not part of the tracks
    node = FusionNode(cfg)
    reader = {"Authorization": f"Bearer {bearer_token(READER_KEY.encode())}"}
    writer = {"Authorization": f"Bearer {node.tokens['array-west']}"}
    with TestClient(create_app(node)) as c:
        for path in ("/tracks", "/sensors", "/health", "/metrics"):
            assert c.get(path).status_code == 401
            assert c.get(path, headers=reader).status_code == 200
            assert c.get(path, headers=writer).status_code == 200  # a node may read too
        token = bearer_token(READER_KEY.encode())
        assert c.get(f"/tracks?token={token}").status_code == 200  # the dashboard's way
        assert c.get("/tracks?token=" + "0" * 64).status_code == 401
        assert c.get("/").status_code == 200 and c.get("/schema").status_code == 200
        r = c.post("/ingest", content=_message().model_dump_json(), headers=reader)
        assert r.status_code == 401  # a reader may not post readings
        with pytest.raises(WebSocketDisconnect) as closed, c.websocket_connect("/ws/tracks") as ws:
            ws.receive_json()
        assert closed.value.code == 1008
        with c.websocket_connect(f"/ws/tracks?token={token}") as ws:
            assert ws.receive_json()["type"] == "hello"
    assert node.rejected["unauthorized_read"] == 6 and node.rejected["unauthorized"] == 1


def test_reading_stays_open_without_readers_and_reader_keys_are_their_own(network):
    node = FusionNode(network)
    with TestClient(create_app(node)) as c:
        assert c.get("/tracks").status_code == 200
    data = network.model_dump(mode="json")
    data["readers"] = [{"id": "dash", "key": data["nodes"][0]["key"]}]
    with pytest.raises(ConfigError, match="readers"):
        parse_config(data)  # a node's key would make the reader a writer
    data["readers"] = [{"id": "dash", "key": "short"}]
    with pytest.raises(ConfigError, match=r"readers\[dash\]\.key"):
        parse_config(data)
