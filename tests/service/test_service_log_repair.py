"""``fusetrack log check|recover`` and ``log.durability`` (issue 18, item 4): a damaged or
foreign log is reported with what is wrong; what still reads back is copied into a new log that
a node resumes from."""

from __future__ import annotations

import json
import sqlite3

import numpy as np
import pytest

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.service.config import parse_config
from fusetrack.service.log import DurableLog
from fusetrack.service.log_repair import check_log, recover_log
from fusetrack.service.node import FusionNode
from fusetrack.service.replay import demo_scenario
from fusetrack.service.schema import SensorMessage, reading_from_vector


def _write_log(path, network, duration=20.0):
    clock = [0.0]
    node = FusionNode(network, wall=lambda: clock[0], log=DurableLog(path))
    owner, kinds = network.owner(), {s.id: s.kind for s in network.sensors}
    for i, x in enumerate(demo_scenario(network, seed=3, duration=duration).readings):
        who = owner[x.sensor]
        m = SensorMessage(
            node=who,
            seq=i + 1,
            sensor=x.sensor,
            time=x.time,
            reading=reading_from_vector(kinds[x.sensor], x.value),
        )
        assert node.ingest_message(m, who).accepted
    clock[0] += 10.0
    node.advance()
    node.log.close()
    with sqlite3.connect(path) as db:
        n = db.execute("SELECT count(*) FROM messages").fetchone()[0]
        t = db.execute("SELECT count(*) FROM ticks").fetchone()[0]
    return n, t


def test_a_sound_log_checks_ok_with_its_counts_and_config(tmp_path, network, capsys):
    path = tmp_path / "node.sqlite"
    n, t = _write_log(path, network)
    report = check_log(path, network)
    assert report.ok and report.counts["messages"] == n and report.counts["ticks"] == t
    assert report.counts["last tick"] == t
    other = network.model_copy(
        update={"fusion": network.fusion.model_copy(update={"rate_hz": 4.0})}
    )
    assert any("another config" in p for p in check_log(path, other).problems)
    assert main(["log", "check", str(path)]) == 0
    assert f"messages: {n}" in capsys.readouterr().out
    assert main(["log", "check", str(tmp_path / "missing.sqlite")]) == 2


def test_bad_rows_are_reported_and_recovery_keeps_what_reads_back(tmp_path, network, capsys):
    path = tmp_path / "node.sqlite"
    n, _ = _write_log(path, network)
    with sqlite3.connect(path) as db:
        db.execute("UPDATE messages SET body = '{bad' WHERE id = 100")
        first_naming = min(
            k
            for k, ids in db.execute("SELECT tick, message_ids FROM ticks")
            if 100 in json.loads(ids)
        )
    with pytest.raises(ConfigError, match="log recover"):
        FusionNode(network, log=DurableLog(path))  # the node refuses it and names the way out
    assert main(["log", "check", str(path)]) == 1
    assert "1 message row(s) do not read back" in capsys.readouterr().out
    new = tmp_path / "recovered.sqlite"
    assert main(["log", "recover", str(path), "--out", str(new)]) == 0
    got = check_log(new, network)
    assert got.ok and got.counts["messages"] == n - 1
    assert got.counts["ticks"] == first_naming - 1  # the ticks before the one that fused it
    node = FusionNode(network, wall=lambda: 0.0, log=DurableLog(new))
    assert node.resumed_ticks == first_naming - 1
    # the readings of the ticks left out wait to be fused again
    assert node.aligner.pending > 0
    with pytest.raises(ConfigError, match="does not exist yet"):
        recover_log(path, new)


def test_a_damaged_page_is_reported_and_stepped_over(tmp_path, network):
    path = tmp_path / "node.sqlite"
    n, _ = _write_log(path, network, duration=40.0)
    data = bytearray(path.read_bytes())
    page = 4096
    assert len(data) > 12 * page
    data[6 * page : 7 * page] = np.random.default_rng(0).bytes(page)
    path.write_bytes(bytes(data))
    report = check_log(path)
    assert not report.ok
    new = tmp_path / "recovered.sqlite"
    got = recover_log(path, new)
    assert 0 < len(got.messages) < n
    assert check_log(new, network).ok
    FusionNode(network, wall=lambda: 0.0, log=DurableLog(new))  # resumes


def test_random_bytes_are_not_a_log(tmp_path):
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(np.random.default_rng(1).bytes(5000))
    report = check_log(junk)
    assert not report.ok and "not a readable SQLite database" in report.problems[0]


def test_durability_full_is_sqlite_synchronous_full(tmp_path, network):
    """``log.durability: full`` commits with ``synchronous=FULL`` (2), the default ``normal``
    with NORMAL (1); ``log: PATH`` stays short for ``log: {path: PATH}``."""
    data = network.model_dump(mode="json")
    data["log"] = {"path": str(tmp_path / "a.sqlite"), "durability": "full"}
    cfg = parse_config(data)
    assert cfg.log.durability == "full"
    from fusetrack.service.server import build_node

    node = build_node(cfg)
    assert node.log.db.execute("PRAGMA synchronous").fetchone()[0] == 2
    node.log.close()
    data["log"] = str(tmp_path / "b.sqlite")
    cfg = parse_config(data)
    assert cfg.log.path == str(tmp_path / "b.sqlite") and cfg.log.durability == "normal"
    node = build_node(cfg)
    assert node.log.db.execute("PRAGMA synchronous").fetchone()[0] == 1
    node.log.close()
    data["log"] = {"path": "c.sqlite", "durability": "fast"}
    with pytest.raises(ConfigError, match=r"log\.durability"):
        parse_config(data)
