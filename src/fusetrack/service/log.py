"""The durable log of a fusion node: every accepted message and every published track state.

One SQLite file (write-ahead journal) with three tables:

* ``messages(id, node, seq, sensor, time, received, body)``: each accepted message, ``body`` its
  JSON exactly as validated; ``id`` is the reading's arrival number;
* ``ticks(tick, time, message_ids, body)``: each fusion tick, the ids of the readings it fused
  (in fusion order) and what it published: one :class:`~.schema.TrackState` (a single-target
  tracker), or a JSON list of them (the multi-target tracker: none, one or several);
* ``meta(key, value)``: the tick grid's ``start`` and the network config's fingerprint.

``fusetrack log check FILE`` checks a log, ``fusetrack log recover FILE --out NEW`` copies what
still reads back into a new one (:mod:`.log_repair`).

:func:`replay_log` recomputes the tracks offline from the messages and the tick assignment and
gives the same states (the node's engine is deterministic given its seed); a restarted node
does the same to resume (:meth:`.node.FusionNode.resume`). Messages are committed with each
tick and each HTTP/WebSocket request, so at most one fusion period of UDP messages can be lost
if the process is killed.
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from ..core import ConfigError, invalid
from .alignment import Reading
from .config import NetworkConfig
from .engine import Engine, build_engine
from .schema import SensorMessage, TrackState

_TABLES = """
CREATE TABLE IF NOT EXISTS messages (
    id INTEGER PRIMARY KEY, node TEXT NOT NULL, seq INTEGER NOT NULL, sensor TEXT NOT NULL,
    time REAL NOT NULL, received REAL NOT NULL, body TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS ticks (
    tick INTEGER PRIMARY KEY, time REAL NOT NULL, message_ids TEXT NOT NULL, body TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
"""


def reading_of(message: SensorMessage, reading_id: int, value: np.ndarray | None = None) -> Reading:
    """The reading an accepted message becomes (``value``: ``message.value()``, if known)."""
    cov = None if message.covariance is None else np.asarray(message.covariance, dtype=float)
    z = message.value() if value is None else value
    return Reading(reading_id, message.sensor, message.time, z, cov)


class DurableLog:
    """Append-only SQLite log (see the module docstring)."""

    def __init__(self, path: str | Path, durability: str = "normal") -> None:
        """``durability``: ``normal`` or ``full``, SQLite's ``synchronous`` (see
        :class:`~.config.LogConfig`)."""
        if durability not in ("normal", "full"):
            raise ConfigError(invalid("log.durability", durability, "'normal' or 'full'"))
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.db = sqlite3.connect(self.path, check_same_thread=False, timeout=1.0)
            self.db.execute("PRAGMA journal_mode=WAL")
            self.db.execute(f"PRAGMA synchronous={durability.upper()}")
            self.db.executescript(_TABLES)
            self.db.commit()
            self.db.execute("SELECT count(*) FROM messages").fetchone()
        except (sqlite3.Error, OSError) as err:  # damaged, foreign, locked, a directory (issue 18)
            raise ConfigError(
                invalid(
                    "log",
                    str(self.path),
                    "a fusetrack node log this node can open and write "
                    f"({type(err).__name__}: {err}); if it is damaged, move it aside to start a "
                    f"new log, or `fusetrack log recover {self.path} --out NEW` to save what it holds",
                )
            ) from None

    def check_config(self, fingerprint: str) -> None:
        """Record the network config's fingerprint in a new log; refuse a log written under
        another config (its sensors, keys or models differ: resuming would mix them)."""
        logged = self.meta("config")
        if logged is None:
            self.set_meta("config", fingerprint)
        elif logged != fingerprint:
            raise ConfigError(
                invalid(
                    "log",
                    str(self.path),
                    f"a log written under this config (its fingerprint {logged[:12]} is not this "
                    f"config's {fingerprint[:12]}): start with the config it was written with, "
                    "or give a new log file",
                )
            )

    def next_id(self) -> int:
        row = self.db.execute("SELECT COALESCE(MAX(id), 0) FROM messages").fetchone()
        return int(row[0]) + 1

    def append_message(self, reading_id: int, message: SensorMessage, received: float) -> None:
        self.db.execute(
            "INSERT INTO messages VALUES (?, ?, ?, ?, ?, ?, ?)",
            (
                reading_id,
                message.node,
                message.seq,
                message.sensor,
                message.time,
                received,
                message.model_dump_json(exclude_none=True),
            ),
        )

    def append_messages(
        self, first_id: int, messages: Sequence[SensorMessage], received: float
    ) -> None:
        """:meth:`append_message` of several messages (ids ``first_id``, ``first_id + 1``, ...)
        in one statement."""
        self.db.executemany(
            "INSERT INTO messages VALUES (?, ?, ?, ?, ?, ?, ?)",
            [
                (
                    first_id + i,
                    m.node,
                    m.seq,
                    m.sensor,
                    m.time,
                    received,
                    m.model_dump_json(exclude_none=True),
                )
                for i, m in enumerate(messages)
            ],
        )

    def append_tick(
        self,
        tick: int,
        time: float,
        states: Sequence[TrackState],
        message_ids: Sequence[int],
        single: bool = True,
    ) -> None:
        """Log one tick; ``single``: the tracker publishes exactly one state per tick."""
        if single and len(states) == 1:
            body = states[0].model_dump_json()
        else:
            body = "[" + ",".join(st.model_dump_json() for st in states) + "]"
        self.db.execute(
            "INSERT INTO ticks VALUES (?, ?, ?, ?)",
            (tick, time, json.dumps(list(message_ids)), body),
        )

    def set_meta(self, key: str, value: str) -> None:
        self.db.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, value))
        self.commit()

    def meta(self, key: str) -> str | None:
        row = self.db.execute("SELECT value FROM meta WHERE key = ?", (key,)).fetchone()
        return None if row is None else str(row[0])

    def commit(self) -> None:
        self.db.commit()

    def close(self) -> None:
        self.db.commit()
        self.db.close()

    # -- reading back ------------------------------------------------------------------------
    def messages(self) -> Iterator[tuple[int, SensorMessage]]:
        for rid, body in self.db.execute("SELECT id, body FROM messages ORDER BY id"):
            yield int(rid), SensorMessage.model_validate_json(body)

    def tick_rows(self) -> Iterator[tuple[int, float, list[TrackState], list[int]]]:
        """``(tick, time, published states, fused message ids)`` of every logged tick."""
        rows = self.db.execute("SELECT tick, time, message_ids, body FROM ticks ORDER BY tick")
        for tick, time, ids, body in rows:
            if body.startswith("["):
                states = [TrackState.model_validate(d) for d in json.loads(body)]
            else:
                states = [TrackState.model_validate_json(body)]
            yield int(tick), float(time), states, json.loads(ids)

    def ticks(self) -> Iterator[tuple[TrackState, list[int]]]:
        """Each published state with the ids its tick fused (a tick of several tracks gives
        several; a tick of none, none)."""
        for _, _, states, ids in self.tick_rows():
            for st in states:
                yield st, ids

    def node_times(self) -> dict[str, tuple[float, float]]:
        """node -> (its latest reading's time, the wall time its latest reading was received)."""
        rows = self.db.execute("SELECT node, MAX(time), MAX(received) FROM messages GROUP BY node")
        return {str(n): (float(t), float(r)) for n, t, r in rows}

    def highest_seq(self) -> dict[str, int]:
        rows = self.db.execute("SELECT node, MAX(seq) FROM messages GROUP BY node")
        return {str(n): int(s) for n, s in rows}


def replay_log(cfg: NetworkConfig, log: DurableLog) -> tuple[Engine, list[TrackState]]:
    """Recompute every logged tick from the logged messages; the engine ends where the node was.

    The recomputed states equal the logged ones (the node's engine is deterministic); compare
    them with ``[s for s, _ in log.ticks()]`` to check a log.
    """
    engine, states, _ = replay_ticks(cfg, log)
    return engine, states


def replay_ticks(cfg: NetworkConfig, log: DurableLog) -> tuple[Engine, list[TrackState], int]:
    """:func:`replay_log`, and the last logged tick (0: none)."""
    start = float(log.meta("start") or cfg.fusion.start)
    engine = build_engine(cfg, start)
    readings = {rid: reading_of(m, rid) for rid, m in log.messages()}
    states: list[TrackState] = []
    last = 0
    for tick, time, _, ids in log.tick_rows():
        states.extend(engine.step_all(tick, time, [readings[i] for i in ids]))
        last = tick
    return engine, states, last
