"""Checking and recovering a node's durable log (``fusetrack log check|recover FILE``).

:func:`check_log` opens a log read-only and reports what is wrong with it: SQLite's
``integrity_check``, the three tables and their columns (:mod:`.log`), the network config's
fingerprint (when a config is given), rows that do not read back (a message the schema refuses,
a tick whose states do not parse or that names a reading not in the log) and the counts.

:func:`recover_log` copies what still reads back into a fresh log: every readable message, and
the ticks from the first one up to the first that is missing or does not read back (a resumed
node re-runs the ticks in order; the readings of the ticks left out are fused again). Rows in
damaged pages are stepped over one row id at a time, so one bad page loses only its rows.
"""

from __future__ import annotations

import json
import sqlite3
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from ..core import ConfigError, invalid
from .config import NetworkConfig
from .log import DurableLog
from .schema import SensorMessage, TrackState

COLUMNS: dict[str, tuple[str, ...]] = {
    "messages": ("id", "node", "seq", "sensor", "time", "received", "body"),
    "ticks": ("tick", "time", "message_ids", "body"),
    "meta": ("key", "value"),
}
"""The tables of a node log and their columns (:data:`.log._TABLES`)."""

MAX_SKIPPED_ROWS = 10_000  # unreadable row ids stepped over in a row before a table is given up


@dataclass
class LogContents:
    """What could be read from a log: rows that read back, and what did not."""

    meta: dict[str, str] = field(default_factory=dict)
    messages: list[tuple[Any, ...]] = field(default_factory=list)  # raw rows, readable bodies
    ticks: list[tuple[Any, ...]] = field(default_factory=list)  # raw rows of consecutive ticks
    problems: list[str] = field(default_factory=list)
    dropped_messages: int = 0
    dropped_ticks: int = 0


@dataclass
class LogCheck:
    """The result of :func:`check_log`: ``problems`` is empty for a sound log."""

    path: Path
    problems: list[str]
    counts: dict[str, Any]

    @property
    def ok(self) -> bool:
        return not self.problems

    def lines(self) -> list[str]:
        head = f"{self.path}: " + ("ok" if self.ok else f"{len(self.problems)} problem(s)")
        counts = [f"  {k}: {v}" for k, v in self.counts.items()]
        return [head, *counts, *(f"  problem: {p}" for p in self.problems)]


def _open_read_only(path: Path) -> sqlite3.Connection:
    if not path.is_file():
        raise ConfigError(invalid("log", str(path), "an existing node log file"))
    return sqlite3.connect(f"file:{path}?mode=ro", uri=True)


def _readable_rows(
    db: sqlite3.Connection, table: str, problems: list[str]
) -> list[tuple[Any, ...]]:
    """The rows of ``table`` in row-id order, stepping over row ids that raise."""
    cols = ", ".join(COLUMNS[table])
    rows: list[tuple[Any, ...]] = []
    last, skipped, failed = -(2**63), 0, 0
    while skipped < MAX_SKIPPED_ROWS:
        try:
            query = f"SELECT rowid, {cols} FROM {table} WHERE rowid > ? ORDER BY rowid"
            for row in db.execute(query, (last,)):
                last, skipped = row[0], 0
                rows.append(row[1:])
            break
        except sqlite3.DatabaseError as err:
            if failed == 0:
                problems.append(f"table {table}: unreadable rows after row id {last} ({err})")
            failed += 1
            skipped += 1
            last += 1
    if skipped >= MAX_SKIPPED_ROWS:
        problems.append(f"table {table}: gave up after {skipped} unreadable row ids")
    return rows


def _reads_back(body: str, parse: Callable[[str], object]) -> bool:
    try:
        parse(body)
    except (ValidationError, ValueError, TypeError):
        return False
    return True


def _tick_states(body: str) -> list[TrackState]:
    if body.startswith("["):
        return [TrackState.model_validate(d) for d in json.loads(body)]
    return [TrackState.model_validate_json(body)]


def read_log(path: str | Path) -> LogContents:
    """Everything of the log at ``path`` that reads back (see the module docstring)."""
    out = LogContents()
    db = _open_read_only(Path(path))
    try:
        try:
            for table, cols in COLUMNS.items():
                found = tuple(r[1] for r in db.execute(f"PRAGMA table_info({table})"))
                if found != cols:
                    out.problems.append(f"table {table} has columns {found}, expected {cols}")
        except sqlite3.DatabaseError as err:
            out.problems.append(f"not a readable SQLite database ({err})")
            return out
        if out.problems:
            return out
        out.meta = {str(k): str(v) for k, v in _readable_rows(db, "meta", out.problems)}
        for row in _readable_rows(db, "messages", out.problems):
            if isinstance(row[6], str) and _reads_back(row[6], SensorMessage.model_validate_json):
                out.messages.append(row)
            else:
                out.dropped_messages += 1
        _keep_consecutive_ticks(out, _readable_rows(db, "ticks", out.problems))
    finally:
        db.close()
    if out.dropped_messages:
        out.problems.append(f"{out.dropped_messages} message row(s) do not read back")
    return out


def _keep_consecutive_ticks(out: LogContents, rows: list[tuple[Any, ...]]) -> None:
    """Keep the ticks from the first up to the first missing, unreadable one or one naming a
    reading not kept; count the rest as dropped."""
    ids = {int(r[0]) for r in out.messages}
    for i, row in enumerate(rows):
        tick, _, message_ids, body = row
        previous = out.ticks[-1][0] if out.ticks else None
        try:
            named = json.loads(message_ids)
            sound = (
                isinstance(tick, int)
                and (previous is None or tick == previous + 1)
                and isinstance(named, list)
                and all(isinstance(m, int) and m in ids for m in named)
                and _reads_back(body, _tick_states)
            )
        except (ValueError, TypeError):
            sound = False
        if not sound:
            out.dropped_ticks = len(rows) - i
            out.problems.append(
                f"tick {tick}: {out.dropped_ticks} tick row(s) from here are missing a previous "
                "tick, do not read back or name readings not in the log"
            )
            return
        out.ticks.append(row)
    if out.ticks and "start" not in out.meta:
        out.problems.append("meta has no 'start' (the tick grid's origin): ticks cannot resume")


def check_log(path: str | Path, cfg: NetworkConfig | None = None) -> LogCheck:
    """Check the log at ``path`` (see the module docstring); ``cfg``: also its fingerprint."""
    p = Path(path)
    contents = read_log(p)
    problems = list(contents.problems)
    db = _open_read_only(p)
    try:
        verdict = [str(r[0]) for r in db.execute("PRAGMA integrity_check")]
        if verdict != ["ok"]:
            problems.insert(0, "SQLite integrity_check: " + "; ".join(verdict[:5]))
    except sqlite3.DatabaseError as err:
        if not problems:
            problems.append(f"SQLite integrity_check failed ({err})")
    finally:
        db.close()
    logged = contents.meta.get("config")
    if cfg is not None and logged != cfg.fingerprint():
        problems.append(
            f"written under another config (fingerprint {str(logged)[:12]}, this config's is "
            f"{cfg.fingerprint()[:12]})"
        )
    per_node = Counter(str(r[1]) for r in contents.messages)
    times = [float(r[4]) for r in contents.messages]
    counts: dict[str, Any] = {
        "messages": len(contents.messages),
        "messages per node": dict(sorted(per_node.items())),
        "reading times": f"{min(times):.3f} .. {max(times):.3f}" if times else "none",
        "ticks": len(contents.ticks),
        "last tick": contents.ticks[-1][0] if contents.ticks else None,
        "config fingerprint": str(logged)[:12] if logged else None,
    }
    return LogCheck(p, problems, counts)


def recover_log(source: str | Path, target: str | Path) -> LogContents:
    """Copy what reads back of the log ``source`` into a new log ``target`` (which must not
    exist); returns what was read, with what was dropped."""
    dst = Path(target)
    if dst.exists():
        raise ConfigError(invalid("--out", str(dst), "a path that does not exist yet"))
    contents = read_log(source)
    if "start" not in contents.meta:
        contents.dropped_ticks += len(contents.ticks)
        contents.ticks = []
    log = DurableLog(dst)
    try:
        for key, value in contents.meta.items():
            log.set_meta(key, value)
        log.db.executemany("INSERT INTO messages VALUES (?, ?, ?, ?, ?, ?, ?)", contents.messages)
        log.db.executemany("INSERT INTO ticks VALUES (?, ?, ?, ?)", contents.ticks)
        log.commit()
    finally:
        log.close()
    return contents
